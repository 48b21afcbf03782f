//! `report.html`: one self-contained page per output folder (issue 26) — the case's inputs,
//! the summary as tables (in the run's units: it reads the folder's own `summary.json`),
//! every plot embedded (base64 PNG) with a caption saying what it shows, and the list of the
//! folder's data files. No scripts or styles from elsewhere; a small inline script checks on
//! load that every image decoded and records the result on `<body data-check=…>` (what the
//! headless-browser test in `tests/report_html.rs` reads).

use std::fmt::Write as _;
use std::path::Path;

use base64::Engine as _;

/// What each plot shows, by file name (prefix for the per-stabilizer and per-quantity
/// ones); `None` for a file this list does not know (captioned by its name).
pub fn caption(file: &str) -> Option<String> {
    let stem = file.trim_end_matches(".png");
    let fixed: &[(&str, &str)] = &[
        ("axial_force", "Effective axial force along the string (tension +); the neutral point is where it crosses zero."),
        ("axial_stress", "Axial stress along the string."),
        ("side_force", "Contact (side) force per site along the string: where the string touches the wall and how hard (in an ensemble: each stabilizer's largest side force against the varied input it follows most)."),
        ("surface_torque", "Torque along the string, from the bit to the surface."),
        ("bha_deflection", "The BHA's lateral deflection in the hole, with the bit's side force and tilt."),
        ("fe_vs_soft_string", "The FE stiff-string loads against the soft-string (Johancsik) model."),
        ("tension_torque", "Tension–torque envelope of the surface pipe (API RP 7G) with the operating points along the string."),
        ("bit_displacement", "Axial displacement of the bit over time."),
        ("energy", "Energy balance of the time integration: kinetic, strain, work done, dissipated."),
        ("broomstick", "Broomstick: hook load (as the weight indicator reads it where the case has a [rig]) against bit depth per mode and friction, with the pipe's tensile limit; measured loads as points where given."),
        ("broomstick_torque", "Surface torque against bit depth per rotating mode and friction; measured torques as points where given."),
        ("torque", "Surface torque against bit depth: measured (points) and modelled at the calibrated friction factors (lines)."),
        ("neutral_point", "Neutral point of the variants against the varied input it follows most (a line per combination of the other inputs; points where the variants are scattered rows)."),
        ("posterior", "Posterior of the friction factors given the measurements (darker = more probable), with the MAP and the 95 % intervals on the axes."),
        ("residuals", "Hook-load residuals (measured − modelled at the calibrated friction) against bit depth, per mode: a trend with depth means a wrong string or survey, not friction."),
        ("residuals_torque", "Torque residuals (measured − modelled) against bit depth."),
        ("campbell", "Campbell diagram: the BHA's lateral natural frequencies against rpm with the 1×, blade-pass and backward-whirl excitations; crossings are critical speeds."),
        ("mode_shapes", "Lateral mode shapes of the BHA as it lies in the hole."),
        ("tendency_build", "Build rate (°/30 m) over the map's axis, one line per weight on bit."),
        ("tendency_turn", "Turn rate over toolface, one line per weight on bit."),
        ("tendency_equilibrium", "Equilibrium curvature (the hole curvature the assembly holds) over stab1's position, one line per WOB."),
        ("stability", "Time-step stability of the integration."),
        ("precision", "f32 against f64 results."),
    ];
    if let Some((_, c)) = fixed.iter().find(|(s, _)| *s == stem) {
        return Some(c.to_string());
    }
    let prefixed: &[(&str, &str)] = &[
        ("orbit_", "Orbit of the stabilizer's centre in the hole (lateral displacement) inside its clearance circle"),
        ("lateral_", "Lateral displacement of the stabilizer over time"),
        ("contact_force_", "Contact force of the stabilizer over time"),
        ("whirl_map_", "Whirl class of the stabilizer over the swept inputs"),
        ("whirl_", "Whirl spectrum of the stabilizer's lateral motion (forward +, backward −)"),
        ("spin_", "Spin of the stabilizer over time"),
        ("hist_", "Distribution of the quantity over the Monte Carlo samples, with P10/P50/P90"),
        ("scatter_", "The quantity against an uncertain input, one point per sample"),
        ("tornado_", "Rank correlation of the quantity with each uncertain input"),
        ("sobol_", "Sobol sensitivity indices of the quantity (first order and total)"),
        ("convergence_", "The estimate's convergence with the number of samples, with its confidence band"),
    ];
    prefixed
        .iter()
        .find(|(p, _)| stem.starts_with(p))
        .map(|(p, c)| format!("{c}: {}.", stem[p.len()..].replace('_', " ")))
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn scalar(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Number(n) => match n.as_f64() {
            Some(x) if x != 0.0 && (x.abs() >= 1e6 || x.abs() < 1e-3) => format!("{x:.4e}"),
            Some(x) if x.fract() != 0.0 => format!("{}", (x * 1e4).round() / 1e4),
            _ => n.to_string(),
        },
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Null => "–".into(),
        other => other.to_string(),
    }
}

/// The summary as HTML tables: scalars of an object in one key/value table, each nested
/// object a table of its own (headed by its path), an array of objects one table with a
/// column per key, an array of scalars on one line (the first 40).
fn tables(path: &str, v: &serde_json::Value, out: &mut String) {
    use serde_json::Value;
    match v {
        Value::Object(o) => {
            let scalars: Vec<(&String, &Value)> = o
                .iter()
                .filter(|(_, x)| !x.is_object() && !is_table_array(x))
                .collect();
            if !scalars.is_empty() {
                if !path.is_empty() {
                    let _ = write!(out, "<h3>{}</h3>", escape(path));
                }
                out.push_str("<table>");
                for (k, x) in scalars {
                    let text = match x {
                        Value::Array(a) => {
                            let mut t: Vec<String> = a.iter().take(40).map(scalar).collect();
                            if a.len() > 40 {
                                t.push(format!("… ({} in all)", a.len()));
                            }
                            t.join(", ")
                        }
                        other => scalar(other),
                    };
                    let _ = write!(
                        out,
                        "<tr><th>{}</th><td>{}</td></tr>",
                        escape(k),
                        escape(&text)
                    );
                }
                out.push_str("</table>");
            }
            for (k, x) in o.iter().filter(|(_, x)| x.is_object() || is_table_array(x)) {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                tables(&p, x, out);
            }
        }
        Value::Array(a) if is_table_array(v) => {
            let mut keys: Vec<String> = Vec::new();
            for row in a {
                if let Value::Object(o) = row {
                    for k in o.keys() {
                        if !keys.contains(k) {
                            keys.push(k.clone());
                        }
                    }
                }
            }
            let _ = write!(
                out,
                "<h3>{}</h3><div class=\"wide\"><table><tr>",
                escape(path)
            );
            for k in &keys {
                let _ = write!(out, "<th>{}</th>", escape(k));
            }
            out.push_str("</tr>");
            for row in a.iter().take(200) {
                out.push_str("<tr>");
                for k in &keys {
                    let cell = row.get(k).map_or(String::new(), |x| match x {
                        Value::Array(a) if a.iter().all(|y| !y.is_object() && !y.is_array()) => {
                            a.iter().map(scalar).collect::<Vec<_>>().join(", ")
                        }
                        Value::Object(_) | Value::Array(_) => x.to_string(),
                        other => scalar(other),
                    });
                    let _ = write!(out, "<td>{}</td>", escape(&cell));
                }
                out.push_str("</tr>");
            }
            if a.len() > 200 {
                let _ = write!(
                    out,
                    "<tr><td colspan=\"{}\">… {} rows in all</td></tr>",
                    keys.len(),
                    a.len()
                );
            }
            out.push_str("</table></div>");
        }
        _ => {}
    }
}

fn is_table_array(v: &serde_json::Value) -> bool {
    matches!(v, serde_json::Value::Array(a) if !a.is_empty() && a.iter().all(|x| x.is_object()))
}

/// Writes `dir/report.html` for the outputs in `dir` (its `summary.json`, plots and data
/// files), `command` naming what made them and `case` the case file (its text shown as the
/// inputs; `None` for none).
pub fn write(dir: &Path, command: &str, case: Option<&Path>) -> std::io::Result<()> {
    let summary: serde_json::Value = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(serde_json::Value::Null);
    let title = summary
        .get("title")
        .and_then(|t| t.as_str())
        .unwrap_or("holewall")
        .to_string();
    let mut files: Vec<String> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "report.html" && !n.contains(".tmp"))
        .collect();
    files.sort();
    let units = match crate::display_units::get() {
        crate::display_units::UnitSystem::Si => "SI",
        crate::display_units::UnitSystem::Field => "oilfield units (ft, klbf, kft·lbf, psi, ppg)",
    };
    let mut html = String::new();
    let _ = write!(
        html,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{t}</title><style>\
         body{{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}}\
         table{{border-collapse:collapse;margin:0.5em 0 1.5em}}\
         th,td{{border:1px solid #ccc;padding:3px 8px;text-align:left;font-size:90%}}\
         th{{background:#f3f3f3}} .wide{{overflow-x:auto}} figure{{margin:1.5em 0}} img{{max-width:100%}}\
         figcaption{{color:#444;font-size:95%}} pre{{background:#f7f7f7;padding:1em;overflow:auto}}\
         </style></head><body data-check=\"pending\">\n<h1>{t}</h1>\n\
         <p><code>holewall {c}</code>; outputs in {u}. Contents: <a href=\"#summary\">summary</a>, \
         <a href=\"#plots\">plots</a>, <a href=\"#files\">data files</a>, \
         <a href=\"#inputs\">inputs</a>.</p>\n",
        t = escape(&title),
        c = escape(command),
        u = units
    );
    if let Some(w) = summary.get("warnings").and_then(|w| w.as_array()) {
        if !w.is_empty() {
            html.push_str("<h2>Warnings</h2><ul>");
            for x in w {
                let _ = write!(html, "<li>{}</li>", escape(&scalar(x)));
            }
            html.push_str("</ul>");
        }
    }
    html.push_str("<h2 id=\"summary\">Summary</h2>\n");
    let mut t = String::new();
    tables("", &summary, &mut t);
    html.push_str(&t);
    html.push_str("<h2 id=\"plots\">Plots</h2>\n");
    let pngs: Vec<&String> = files.iter().filter(|f| f.ends_with(".png")).collect();
    if pngs.is_empty() {
        html.push_str("<p>This run drew no plots.</p>");
    }
    for f in pngs {
        let bytes = std::fs::read(dir.join(f))?;
        let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
        let cap = caption(f).unwrap_or_else(|| f.clone());
        let _ = writeln!(
            html,
            "<figure><img src=\"data:image/png;base64,{data}\" alt=\"{a}\">\
             <figcaption><b>{f}</b>: {c}</figcaption></figure>",
            a = escape(&cap),
            f = escape(f),
            c = escape(&cap)
        );
    }
    html.push_str("<h2 id=\"files\">Data files</h2><ul>");
    for f in files.iter().filter(|f| !f.ends_with(".png")) {
        let _ = write!(html, "<li><a href=\"{0}\">{0}</a></li>", escape(f));
    }
    html.push_str("</ul>\n<h2 id=\"inputs\">Inputs</h2>\n");
    match case.and_then(|p| std::fs::read_to_string(p).ok().map(|t| (p, t))) {
        Some((p, text)) => {
            let _ = write!(
                html,
                "<p>{}</p><pre>{}</pre>",
                escape(&p.display().to_string()),
                escape(&text)
            );
        }
        None => html.push_str("<p>No case file.</p>"),
    }
    html.push_str(
        "\n<script>\nwindow.addEventListener('load', function () {\n\
         var imgs = document.images, bad = 0;\n\
         for (var i = 0; i < imgs.length; i++) {\n\
         if (!imgs[i].complete || imgs[i].naturalWidth === 0) { bad++; }\n}\n\
         document.body.setAttribute('data-check', bad === 0 ? 'ok images=' + imgs.length : \
         'broken images=' + bad);\n});\n</script>\n</body></html>\n",
    );
    crate::atomic_file::write_atomic(&dir.join("report.html"), html.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_plot_the_commands_draw_has_a_caption() {
        for f in [
            "axial_force.png",
            "broomstick.png",
            "posterior.png",
            "orbit_stab1.png",
            "hist_hook_load_n.png",
            "tornado_hook_load_n.png",
            "whirl_map_stab1.png",
            "campbell.png",
            "tension_torque.png",
        ] {
            assert!(caption(f).is_some(), "{f}");
        }
        assert!(caption("mystery.png").is_none());
    }
}
