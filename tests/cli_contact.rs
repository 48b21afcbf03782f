//! `holewall contact`: JSON Lines in, JSON Lines out; bad input → message naming line and
//! key, exit code 2, no output.

use std::io::Write;
use std::process::{Command, Stdio};

use serde_json::{json, Value};

fn run(args: &[&str], stdin: &str) -> (i32, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_holewall"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).to_string(),
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

fn good_line() -> Value {
    json!({
        "x0": [0.0, 0.0, -1000.0], "n": [0.0, 0.0, 2.0],
        "hole_radius": 0.1075, "disk_radius": 0.1, "k_e": 6e7, "m": 1.5, "c": 8e3,
        "mu_t": 0.4, "mu_l": 0.3, "eps": 1e-3, "friction": "split", "mode": "dynamic",
        "x": [0.0085, 0.0, -999.9], "v": [0.01, 0.2, 0.0], "omega": 12.566
    })
}

#[test]
fn computes_each_line_in_order_on_cpu_and_gpu() {
    let mut second = good_line();
    second["x"] = json!([0.0, 0.001, -1000.0]); // inside the clearance
    second["friction"] = json!("coupled");
    let mut third = good_line();
    third["mode"] = json!("static");
    third["m"] = json!(0.6666666666666666);
    third["soft_blend"] = json!(1e-4);
    let input = format!("{}\n\n{}\n{}\n", good_line(), second, third);
    let mut outputs = Vec::new();
    for backend in ["cpu", "gpu"] {
        let (code, stdout, stderr) = run(&["contact", "--backend", backend], &input);
        assert_eq!(code, 0, "{backend}: {stderr}");
        let lines: Vec<Value> = stdout
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0]["contact"], json!(true));
        assert_eq!(lines[1]["contact"], json!(false));
        assert_eq!(lines[1]["g"], json!([0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
        assert_eq!(lines[2]["contact"], json!(true));
        assert_eq!(lines[0]["K"].as_array().unwrap().len(), 6);
        assert_eq!(lines[0]["K"][0].as_array().unwrap().len(), 3);
        // Static mode: no damping matrix.
        assert!(lines[2]["C"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|r| r.as_array().unwrap())
            .all(|x| x.as_f64() == Some(0.0)));
        // Hand check of line 1: delta = 0.0085 − 0.0075 = 1e-3, f_e = 6e7·(1e-3)^1.5,
        // f_d = c·v_u = 8e3·0.01; u = +x, so g_x = N.
        let n = 6e7 * 1e-3f64.powf(1.5) + 8e3 * 0.01;
        let gx = lines[0]["g"][0].as_f64().unwrap();
        assert!((gx - n).abs() <= 1e-12 * n, "{backend}: g_x {gx} vs N {n}");
        outputs.push(lines);
    }
    for (a, b) in outputs[0].iter().zip(&outputs[1]) {
        let fa: Vec<f64> = a["g"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let fb: Vec<f64> = b["g"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        for (x, y) in fa.iter().zip(&fb) {
            assert!((x - y).abs() <= 1e-12 * x.abs().max(1.0));
        }
    }
    // f32 asked: the numbers are f32 values.
    let (code, stdout, _) = run(
        &["contact", "--backend", "cpu", "--precision", "f32"],
        &input,
    );
    assert_eq!(code, 0);
    let first: Value = serde_json::from_str(stdout.lines().next().unwrap()).unwrap();
    let gx = first["g"][0].as_f64().unwrap();
    assert_eq!(
        first["g"][0].to_string(),
        (gx as f32).to_string(),
        "f32 results print as f32"
    );
    let n = 6e7 * 1e-3f64.powf(1.5) + 8e3 * 0.01;
    assert!((gx - n).abs() <= 1e-5 * n);
}

#[test]
fn reads_a_file_argument() {
    let dir = std::env::temp_dir().join(format!("holewall-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("in.jsonl");
    std::fs::write(&path, format!("{}\n", good_line())).unwrap();
    let (code, stdout, _) = run(&["contact", "--backend", "cpu", path.to_str().unwrap()], "");
    assert_eq!(code, 0);
    assert_eq!(stdout.lines().count(), 1);
    let (code, stdout, stderr) = run(
        &[
            "contact",
            "--backend",
            "cpu",
            dir.join("missing.jsonl").to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(code, 2);
    assert!(stdout.is_empty() && stderr.contains("missing.jsonl"));
}

/// Each bad line, placed as line 2 after a good line: exit 2, no output at all, and a
/// message naming line 2 and the key.
#[test]
fn bad_input_is_rejected_with_line_and_key() {
    type Edit = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "disk_radius",
            Box::new(|v| v["disk_radius"] = json!(0.2)),
            "clearance",
        ),
        (
            "n",
            Box::new(|v| v["n"] = json!([0.0, 0.0, 0.0])),
            "zero vector",
        ),
        ("k_e", Box::new(|v| v["k_e"] = json!(0.0)), "out of range"),
        ("k_e", Box::new(|v| v["k_e"] = json!(-5.0)), "out of range"),
        ("m", Box::new(|v| v["m"] = json!(0.0)), "out of range"),
        ("eps", Box::new(|v| v["eps"] = json!(0.0)), "out of range"),
        ("eps", Box::new(|v| v["eps"] = json!(-1e-3)), "out of range"),
        ("c", Box::new(|v| v["c"] = json!(-1.0)), "out of range"),
        (
            "mu_t",
            Box::new(|v| v["mu_t"] = json!(-0.1)),
            "out of range",
        ),
        (
            "soft_blend",
            Box::new(|v| v["soft_blend"] = json!(0.0)),
            "out of range",
        ),
        (
            "hole_radius",
            Box::new(|v| v["hole_radius"] = json!("wide")),
            "expected a number",
        ),
        ("bogus", Box::new(|v| v["bogus"] = json!(1)), "unknown key"),
        (
            "friction",
            Box::new(|v| v["friction"] = json!("sticky")),
            "unknown value",
        ),
        (
            "mode",
            Box::new(|v| v["mode"] = json!("quasi")),
            "unknown value",
        ),
        ("x", Box::new(|v| v["x"] = json!([1.0, 2.0])), "array of 3"),
        (
            "omega",
            Box::new(|v| {
                v.as_object_mut()
                    .unwrap()
                    .remove("omega")
                    .map(|_| ())
                    .unwrap()
            }),
            "missing",
        ),
    ];
    for (key, edit, words) in cases {
        let mut bad = good_line();
        edit(&mut bad);
        let input = format!("{}\n{}\n{}\n", good_line(), bad, good_line());
        for backend in ["cpu", "auto"] {
            let (code, stdout, stderr) = run(&["contact", "--backend", backend], &input);
            assert_eq!(code, 2, "{key}: exit code; stderr {stderr}");
            assert!(
                stdout.is_empty(),
                "{key}: output written despite a bad line"
            );
            assert!(
                stderr.contains("<stdin>:2:"),
                "{key}: line not named: {stderr}"
            );
            assert!(stderr.contains(key), "{key}: key not named: {stderr}");
            assert!(
                stderr.contains(words),
                "{key}: message lacks {words:?}: {stderr}"
            );
            assert!(!stderr.contains("panicked"), "{key}: panic: {stderr}");
        }
    }
    // Non-finite numbers: JSON has no NaN or Infinity; out-of-range numbers overflow f64.
    for text in ["NaN", "Infinity", "-Infinity", "1e999"] {
        let line = good_line().to_string().replace("12.566", text);
        let input = format!("{}\n{}\n", good_line(), line);
        let (code, stdout, stderr) = run(&["contact", "--backend", "cpu"], &input);
        assert_eq!(code, 2, "{text}");
        assert!(stdout.is_empty());
        assert!(
            stderr.contains("<stdin>:2:") && stderr.contains("finite"),
            "{text}: {stderr}"
        );
    }
    // Out of f32 range when f32 is asked.
    let mut big = good_line();
    big["k_e"] = json!(1e60);
    let (code, stdout, stderr) = run(
        &["contact", "--backend", "cpu", "--precision", "f32"],
        &format!("{big}\n"),
    );
    assert_eq!(code, 2);
    assert!(
        stdout.is_empty() && stderr.contains("k_e") && stderr.contains("f32"),
        "{stderr}"
    );
    // Not an object.
    let (code, _, stderr) = run(&["contact", "--backend", "cpu"], "[1, 2]\n");
    assert_eq!(code, 2);
    assert!(stderr.contains("<stdin>:1:"));
}

fn run_env(args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_holewall"))
        .args(args)
        .envs(env.iter().copied())
        .env_remove("HOLEWALL_REQUIRE_GPU")
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).to_string(),
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

#[test]
fn adapter_choice_follows_the_environment() {
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/contact_examples.jsonl");
    let lines = std::fs::read_to_string(case).unwrap().lines().count();
    // No backend that can open an adapter: auto falls back to the CPU with one notice.
    let (code, stdout, stderr) = run_env(&["contact", case], &[("WGPU_BACKEND", "metal")]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(stdout.lines().count(), lines);
    let notices: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("using the CPU backend"))
        .collect();
    assert_eq!(notices.len(), 1, "{stderr}");
    // --backend gpu does not fall back.
    let (code, stdout, stderr) = run_env(
        &["contact", "--backend", "gpu", case],
        &[("WGPU_BACKEND", "metal")],
    );
    assert_eq!(code, 1);
    assert!(
        stdout.is_empty() && stderr.contains("no GPU adapter"),
        "{stderr}"
    );
    // WGPU_ADAPTER_NAME that matches no adapter is an error naming the adapters seen.
    let (code, stdout, stderr) = run_env(
        &["contact", "--backend", "gpu", case],
        &[("WGPU_ADAPTER_NAME", "no-such-adapter-xyz")],
    );
    assert_eq!(code, 1);
    assert!(
        stdout.is_empty() && stderr.contains("no-such-adapter-xyz"),
        "{stderr}"
    );
}

#[test]
fn coordinates_parse_correctly_rounded() {
    // 1200 lines of random states written with Rust's shortest round-trip decimals (as any
    // correct writer would): every coordinate read back bit for bit. serde_json's default
    // float parser is not correctly rounded (1296 of these 10800 came back an ulp off, which
    // moves a 1e-9 m penetration at 1234 m MD by 1e-4 of its force); the `float_roundtrip`
    // feature makes it exact.
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let mut off = 0usize;
    for line in 0..1200 {
        let x0: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1500.0..1500.0));
        let x: [f64; 3] = std::array::from_fn(|k| x0[k] + rng.random_range(-0.2..0.2));
        let v: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
        let vec = |a: &[f64; 3]| format!("[{}, {}, {}]", a[0], a[1], a[2]);
        let text = format!(
            r#"{{"x0": {}, "n": [0.0, 0.0, 1.0], "hole_radius": 0.1075, "disk_radius": 0.1, "k_e": 6e7, "m": 1.5, "c": 8e3, "mu_t": 0.4, "mu_l": 0.3, "eps": 1e-3, "friction": "split", "mode": "dynamic", "x": {}, "v": {}, "omega": 12.566}}"#,
            vec(&x0),
            vec(&x),
            vec(&v)
        );
        let q = holewall::cli::contact::parse_line("t.jsonl", line + 1, &text, false).unwrap();
        for (a, b) in
            q.x0.iter()
                .chain(&q.x)
                .chain(&q.v)
                .zip(x0.iter().chain(&x).chain(&v))
        {
            if a.to_bits() != b.to_bits() {
                off += 1;
            }
        }
    }
    assert_eq!(
        off, 0,
        "{off} of 10800 coordinates parsed off by an ulp or more"
    );
}
