//! `report.html` in every output folder (issue 26): the page embeds each of the folder's
//! plots with a caption, the summary as tables and the case's inputs; in a real headless
//! Chromium (the Debian package, installed by `.ci/run`) it loads with no console message
//! and every image decodes. Without Chromium the browser half is skipped loudly — except in
//! CI (`CI=true`), where that fails.

mod common;

use base64::Engine as _;

fn manifest(p: &str) -> String {
    format!("{}/{p}", env!("CARGO_MANIFEST_DIR"))
}

/// The page holds one decodable PNG per plot file of the folder, a caption for each, the
/// summary's title and the inputs.
fn check_page(dir: &std::path::Path, case_text_marker: &str) {
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let pngs: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".png"))
        .collect();
    assert!(!pngs.is_empty(), "{}", dir.display());
    let images: Vec<&str> = html.split("data:image/png;base64,").skip(1).collect();
    assert_eq!(images.len(), pngs.len(), "{}", dir.display());
    for img in images {
        let b64 = &img[..img.find('"').unwrap()];
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(b64)
            .unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }
    for p in &pngs {
        assert!(html.contains(&format!("<b>{p}</b>:")), "{p} has no caption");
        assert!(
            holewall::report_html::caption(p).is_some(),
            "{p}: caption unknown"
        );
    }
    assert!(html.contains("<h2 id=\"summary\">") && html.contains(case_text_marker));
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "not self-contained"
    );
}

/// Loads the page in headless Chromium: `Some(())` when it ran and passed (no console
/// message, every image decoded), `None` without Chromium.
fn check_in_browser(dir: &std::path::Path) -> Option<()> {
    let page = dir.join("report.html");
    let profile = common::scratch_dir(
        "report_html",
        &format!("profile-{}", page.display().to_string().len()),
    );
    let out = std::process::Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--enable-logging=stderr",
            "--v=0",
            &format!("--user-data-dir={}", profile.display()),
            "--dump-dom",
            &format!("file://{}", page.display()),
        ])
        .output()
        .ok()?;
    let dom = String::from_utf8_lossy(&out.stdout);
    let log = String::from_utf8_lossy(&out.stderr);
    let pngs = std::fs::read_dir(dir)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.file_name().to_string_lossy().ends_with(".png"))
        })
        .count();
    assert!(
        dom.contains(&format!("data-check=\"ok images={pngs}\"")),
        "{}: the page's image check did not pass: {}",
        page.display(),
        dom.split("data-check")
            .nth(1)
            .unwrap_or("(no body)")
            .chars()
            .take(80)
            .collect::<String>()
    );
    let console: Vec<&str> = log.lines().filter(|l| l.contains(":CONSOLE")).collect();
    assert!(
        console.is_empty(),
        "{}: console: {console:?}",
        page.display()
    );
    Some(())
}

#[test]
fn every_output_folder_gets_a_report_that_loads_in_a_browser() {
    let dir = common::scratch_dir("report_html", "runs");
    let mut folders = Vec::new();
    // static (with strength and a rig), ensemble (broomstick), calibrate, run (dynamics).
    let broom = manifest("cases/broomstick_tool_joints.toml");
    let runs: Vec<(&str, Vec<String>)> = vec![
        (
            "static",
            vec!["static".into(), manifest("cases/build_and_hold.toml")],
        ),
        (
            "ensemble",
            vec![
                "ensemble".into(),
                broom.clone(),
                "--backend".into(),
                "cpu".into(),
            ],
        ),
        (
            "calibrate",
            vec![
                "calibrate".into(),
                broom.clone(),
                "--measured".into(),
                manifest("cases/broomstick_measured.csv"),
                "--nodes".into(),
                "5".into(),
            ],
        ),
        (
            "run",
            vec!["run".into(), manifest("cases/spinup_short.toml")],
        ),
    ];
    for (name, mut args) in runs {
        let out = dir.join(name);
        args.extend(["--out".into(), out.display().to_string(), "--quiet".into()]);
        let refs: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
        let (code, _, stderr) = common::holewall(&refs);
        assert_eq!(code, 0, "{name}: {stderr}");
        check_page(&out, "[well]");
        folders.push(out);
    }
    // A second run into the same folder replaces it (report.html counts as an output).
    let again = dir.join("static");
    let (code, _, stderr) = common::holewall(&[
        "static",
        &manifest("cases/build_and_hold.toml"),
        "--out",
        again.to_str().unwrap(),
        "--quiet",
        "--units",
        "field",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let html = std::fs::read_to_string(again.join("report.html")).unwrap();
    assert!(html.contains("hook_load_klbf") && html.contains("oilfield units"));
    let mut ran = 0;
    for f in &folders {
        if check_in_browser(f).is_some() {
            ran += 1;
        }
    }
    if ran == 0 {
        assert!(
            std::env::var("CI").is_err(),
            "CI=true but no chromium: .ci/run installs it; the browser check must run in CI"
        );
        eprintln!(
            "\n*** report.html NOT checked in a browser: no `chromium` on this machine \
             (apt-get install chromium); the page's structure was checked ***\n"
        );
    } else {
        println!("report.html checked in headless Chromium in {ran} folders");
    }
}
