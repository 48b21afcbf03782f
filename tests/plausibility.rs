//! Plausibility of inputs (issue 23): a unit mix-up or a typo that would run and give wrong
//! numbers is refused with the likely intent (exit 2, file, line, key); an unusual but
//! possible input runs with a warning on stderr and in `summary.json`.

mod common;

use common::holewall;
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    common::scratch_dir("plaus", name)
}

/// The shipped build-and-hold case (1,500 m; KOP 300 m, 2°/30 m to 30°) on a survey:
/// stations every 30 m, `md_scale` × MD written, `header` on top, `edit` applied to the
/// station list, `mud` as the density.
fn survey_case(
    name: &str,
    header: &str,
    md_scale: f64,
    edit: &dyn Fn(&mut Vec<[f64; 3]>),
    well_extra: &str,
    mud: &str,
) -> (PathBuf, PathBuf) {
    let dir = scratch(name);
    let mut st: Vec<[f64; 3]> = (0..=50)
        .map(|k| {
            let md = 30.0 * k as f64;
            let inc = ((md - 300.0).max(0.0) / 30.0 * 2.0).min(30.0);
            [md, inc, 45.0]
        })
        .collect();
    edit(&mut st);
    let mut csv = String::from(header);
    for s in &st {
        csv.push_str(&format!("{}, {}, {}\n", s[0] * md_scale, s[1], s[2]));
    }
    std::fs::write(dir.join("survey.csv"), csv).unwrap();
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/build_and_hold.toml"),
    )
    .unwrap();
    let rest = &base[base.find("[[hole]]").unwrap()..];
    let text = format!(
        "title = \"survey check\"\n[well]\nprofile = \"survey\"\nsurvey = \"survey.csv\"\n\
         total_md = \"1500 m\"\n{well_extra}\n{}",
        rest.replace("density = \"10 ppg\"", &format!("density = \"{mud}\""))
    );
    let case = dir.join("case.toml");
    std::fs::write(&case, text).unwrap();
    (case, dir.join("out"))
}

fn soft_string(case: &Path, out: &Path) -> (i32, String, String) {
    holewall(&[
        "static",
        case.to_str().unwrap(),
        "--model",
        "soft-string",
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn the_survey_as_meant_runs_without_warnings() {
    let (case, out) = survey_case("ok", "md_m, inc_deg, azi_deg\n", 1.0, &|_| {}, "", "10 ppg");
    let (code, _, stderr) = soft_string(&case, &out);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    // The same survey in feet, saying so in its header, runs too.
    let (case, out) = survey_case(
        "ft",
        "md_ft, inc_deg, azi_deg\n",
        3.280_84,
        &|_| {},
        "",
        "10 ppg",
    );
    let (code, _, stderr) = soft_string(&case, &out);
    assert_eq!(code, 0, "{stderr}");
}

#[test]
fn a_survey_in_feet_without_a_header_is_refused_as_feet() {
    let (case, out) = survey_case("feet", "", 3.280_84, &|_| {}, "", "10 ppg");
    let (code, _, stderr) = soft_string(&case, &out);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("survey.csv") && stderr.contains("survey.csv:51:"),
        "{stderr}"
    );
    assert!(
        stderr.contains("3.28×") && stderr.contains("feet"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing written");
}

#[test]
fn a_dogleg_typo_is_refused_and_a_sharp_build_warned() {
    // 80° more inclination at one station (80°/30 m): a typo.
    let (case, out) = survey_case("typo", "", 1.0, &|s| s[20][1] += 80.0, "", "10 ppg");
    let (code, _, stderr) = soft_string(&case, &out);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("survey.csv:21:") && stderr.contains("typo"),
        "{stderr}"
    );
    assert!(stderr.contains("max_dogleg_deg_per_30m"), "{stderr}");
    // The same survey with the limit raised (a short-radius well) runs, warned.
    let (case, out) = survey_case(
        "typo-allowed",
        "",
        1.0,
        &|s| s[20][1] += 80.0,
        "max_dogleg_deg_per_30m = 100.0",
        "10 ppg",
    );
    let (code, _, stderr) = soft_string(&case, &out);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("warning") && stderr.contains("survey.csv:21:"),
        "{stderr}"
    );
    // 18°/30 m at one station: runs with a warning, in summary.json too.
    let (case, out) = survey_case("sharp", "", 1.0, &|s| s[20][1] += 16.0, "", "10 ppg");
    let (code, _, stderr) = soft_string(&case, &out);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("warning") && stderr.contains("°/30 m"),
        "{stderr}"
    );
    let summary: serde_json::Value = common::json(&out.join("summary.json"));
    assert_eq!(
        summary["warnings"].as_array().map(|w| w.len()),
        Some(1),
        "{summary}"
    );
}

#[test]
fn an_azimuth_past_360_is_refused_with_its_normalised_value() {
    let (case, out) = survey_case("azi", "", 1.0, &|s| s[30][2] = 400.0, "", "10 ppg");
    let (code, _, stderr) = soft_string(&case, &out);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("survey.csv:31:") && stderr.contains("did you mean 40°"),
        "{stderr}"
    );
}

#[test]
fn a_mud_density_outside_drilling_fluids_is_refused_with_the_intent() {
    for (mud, intent) in [
        ("1.2 kg/m3", "lighter than any drilling fluid"),
        ("1.3 ppg", "did you mean \"1.3 sg\""),
        ("12 sg", "did you mean \"12 ppg\""),
    ] {
        let (case, out) = survey_case("mud", "", 1.0, &|_| {}, "", mud);
        let (code, _, stderr) = soft_string(&case, &out);
        assert_eq!(code, 2, "{mud}: {stderr}");
        assert!(
            stderr.contains("mud.density") && stderr.contains(intent),
            "{stderr}"
        );
    }
}

#[test]
fn a_chunk_size_of_zero_is_refused() {
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/ensemble_build_and_hold.toml");
    let out = scratch("chunk").join("out");
    let (code, _, stderr) = holewall(&[
        "ensemble",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--chunk-size",
        "0",
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--chunk-size"), "{stderr}");
}

/// The plausibility checks on the corpus of ordinary wells (`holewall::corpus`, first 100
/// seeds): every well loads with no refusal and no warning; the same surveys written in
/// feet without saying so are all refused as feet, and all load with an `md_ft` header.
#[test]
fn corpus_wells_pass_and_their_feet_surveys_are_caught() {
    let dir = scratch("corpus");
    for seed in 0..100u64 {
        let w = holewall::corpus::write_well(seed, &dir).unwrap();
        let case = holewall::case::load_case(&w.case_path)
            .unwrap_or_else(|e| panic!("seed {seed} refused: {e}"));
        assert!(case.warnings.is_empty(), "seed {seed}: {:?}", case.warnings);
        let csv = w.case_path.with_extension("csv");
        let rows: Vec<String> = std::fs::read_to_string(&csv)
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| {
                let f: Vec<f64> = l.split(',').map(|x| x.trim().parse().unwrap()).collect();
                format!("{}, {}, {}", f[0] * 3.280_84, f[1], f[2])
            })
            .collect();
        std::fs::write(&csv, rows.join("\n") + "\n").unwrap();
        let e = holewall::case::load_case(&w.case_path).unwrap_err();
        assert!(e.message.contains("feet"), "seed {seed}: {e}");
        std::fs::write(&csv, format!("md_ft, inc, azi\n{}\n", rows.join("\n"))).unwrap();
        assert!(
            holewall::case::load_case(&w.case_path).is_ok(),
            "seed {seed}"
        );
    }
}
