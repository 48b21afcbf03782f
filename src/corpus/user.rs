//! The corpus's second style (`holewall bench corpus --style user`): wells drawn the way
//! users write them rather than the way [`super::write_well`] spans them — what that style
//! leaves out: tool joints on the pipe and HWDP (a node and contact site at every joint),
//! reaming and back-reaming, a surface casing above the intermediate one and a washed-out
//! open hole (three hole sections), a tapered string (larger pipe above), pipe grades,
//! wells to 6,000 m, and a weight on bit drawn up to 1.5× the sinusoidal-buckling limit (the
//! `drawn` style stops at it), so drilling and sliding buckle the pipe as users load it.
//! Measured first as an independent probe (stop 68: 280 wells written by a script of their
//! own, run by `holewall static`); this is its generator in the product.

use super::{
    bha_bottom, contact_and_mesh, pick, survey, tube, write_at_wob, write_survey, CorpusWell,
    Trajectory, WellSpec, SIZES,
};
use crate::error::Error;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

/// Tool-joint OD (in) of a pipe of `od` in (API NC connections of the usual sizes).
fn tool_joint_in(od: f64) -> f64 {
    match od {
        x if x < 3.75 => 4.75,
        x if x < 4.5 => 5.25,
        x if x < 5.25 => 6.625,
        x if x < 5.7 => 7.0,
        _ => 7.25,
    }
}

/// Draws well `seed` in the user style and writes it into `dir` (`user_<seed>.toml` and
/// `.csv`); the stream of draws is its own (a seed names another well than `drawn`'s).
pub fn write_user_well(seed: u64, dir: &Path) -> Result<CorpusWell, Error> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x75_73_65_72);
    let trajectory = pick(
        &mut rng,
        &[
            (Trajectory::Vertical, 0.1),
            (Trajectory::BuildAndHold, 0.3),
            (Trajectory::SShaped, 0.25),
            (Trajectory::Horizontal, 0.35),
        ],
    );
    let total_md = rng.random_range(1200.0f64..6000.0).round();
    let (stations, turn) = survey(&mut rng, trajectory, total_md);
    let size = &SIZES[rng.random_range(0..SIZES.len())];
    let shoe = (rng.random_range(0.3..0.75) * total_md).round();
    // A surface casing above the intermediate one (60 %), 2.5–4 in wider.
    let surface = rng
        .random_bool(0.6)
        .then(|| {
            (
                (rng.random_range(0.1..0.6) * shoe).round(),
                size.casing_id_in + pick(&mut rng, &[(2.5, 1.0), (3.5, 1.0), (4.0, 1.0)]),
            )
        })
        .filter(|s| s.0 >= 30.0);
    let washout = pick(&mut rng, &[(1.0, 0.5), (1.02, 0.25), (1.05, 0.25)]);
    let mu_surface = rng.random_range(0.15..0.25);
    let mu_cased = rng.random_range(0.15..0.25);
    let mu_open = rng.random_range(0.2..0.4);
    let sg = rng.random_range(1.0..1.9);
    let collar = size.collars[rng.random_range(0..size.collars.len())];
    let stabilizers = pick(
        &mut rng,
        &[(0usize, 0.15), (1, 0.3), (2, 0.3), (3, 0.15), (4, 0.1)],
    );
    let bend = if rng.random_bool(0.15) {
        rng.random_range(0.5f64..2.0)
    } else {
        0.0
    };
    let under_gauge: Vec<f64> = (0..stabilizers)
        .map(|_| rng.random_range(0.0..0.4))
        .collect();
    let spacing: Vec<f64> = (0..stabilizers)
        .map(|_| rng.random_range(4.0f64..28.0).round())
        .collect();
    let collar_len = rng.random_range(20.0f64..200.0).round();
    let joints = rng.random_bool(0.5);
    let grade = pick(&mut rng, &[("", 1.0), ("G105", 1.0), ("S135", 1.0)]);
    let hwdp_len = if rng.random_bool(0.6) {
        rng.random_range(60.0f64..300.0).round()
    } else {
        0.0
    };
    let tapered = size.hole_in > 8.0 && rng.random_bool(0.3);
    let lower_share = rng.random_range(0.2..0.5);
    let mode = pick(
        &mut rng,
        &[
            ("rotating", 1.0),
            ("drilling", 1.5),
            ("sliding", 1.0),
            ("tripping_in", 1.0),
            ("tripping_out", 1.0),
            ("reaming", 0.75),
            ("back_reaming", 0.75),
        ],
    );
    let rpm = rng.random_range(40.0f64..180.0).round();
    let axial_speed = (rng.random_range(0.1f64..0.6) * 100.0).round() / 100.0;
    let wob_fraction = rng.random_range(0.0..1.5);
    let element: f64 = pick(
        &mut rng,
        &[
            (1.0, 0.1),
            (2.0, 0.1),
            (5.0, 0.15),
            (9.144, 0.15),
            (10.0, 0.25),
            (15.0, 0.1),
            (20.0, 0.1),
            (30.0, 0.05),
        ],
    );
    let bha_element: f64 = pick(&mut rng, &[(0.5f64, 0.3), (1.0, 0.5), (2.0, 0.2)]).min(element);
    let exponent = pick(&mut rng, &[(1.0, 0.7), (1.5, 0.15), (2.0 / 3.0, 0.15)]);
    let k_linear = 10f64.powf(rng.random_range(6.0..9.0));
    let wall_stiffness = k_linear * 1e-3f64.powf(1.0 - exponent);
    let sites = if stabilizers > 0 && rng.random_bool(0.15) {
        "stabilizers"
    } else {
        "all_nodes"
    };

    // The string from the bit up.
    let (mut comps, mut used) = bha_bottom(
        &mut rng,
        collar,
        size.hole_in,
        bend,
        &under_gauge,
        &spacing,
        "",
    );
    let (cod, cid) = collar;
    let rest = (collar_len - used).max(9.0);
    comps.push(tube("collar", rest, cod, cid, ""));
    used += rest;
    let joint = |od: f64| {
        if joints {
            format!("tool_joint_od = \"{} in\"\n", tool_joint_in(od))
        } else {
            String::new()
        }
    };
    if hwdp_len > 0.0 {
        let (od, id) = size.hwdp;
        comps.push(tube("hwdp", hwdp_len, od, id, &joint(od)));
        used += hwdp_len;
    }
    let graded = |od: f64| {
        let mut extra = joint(od);
        if !grade.is_empty() {
            extra.push_str(&format!("grade = \"{grade}\"\n"));
        }
        extra
    };
    let pipe_len = (total_md - used + 1.0).max(1.0).round();
    let (pod, pid) = size.pipe;
    if tapered && pipe_len > 1500.0 {
        let lower = (lower_share * pipe_len).round();
        comps.push(tube("drill_pipe", lower, pod, pid, &graded(pod)));
        let (bod, bid) = if pod < 5.25 {
            (5.5, 4.778)
        } else {
            (5.875, 5.045)
        };
        comps.push(tube("drill_pipe", pipe_len - lower, bod, bid, &graded(bod)));
    } else {
        comps.push(tube("drill_pipe", pipe_len, pod, pid, &graded(pod)));
    }

    let name = format!("user_{seed}");
    let csv_name = write_survey(dir, &name, &stations)?;
    let max_inc = stations.iter().map(|s| s[1]).fold(0.0, f64::max);
    let op_mode = if mode == "drilling" { "rotating" } else { mode };
    let turning = matches!(mode, "rotating" | "drilling" | "reaming" | "back_reaming");
    let moving = !matches!(mode, "rotating" | "drilling");
    let on_bottom = matches!(mode, "drilling" | "sliding");
    let case_text = |wob: f64| {
        let mut t = format!(
            "title = \"user-style well {seed}: {}{}, {total_md} m, {} in hole, {mode}\"\n",
            trajectory.name(),
            if turn { " with turn" } else { "" },
            size.hole_in
        );
        t.push_str(&format!(
            "[well]\nprofile = \"survey\"\nsurvey = \"{csv_name}\"\ntotal_md = \"{total_md} m\"\n"
        ));
        if let Some((bottom, id)) = surface {
            t.push_str(&format!(
                "[[hole]]\nbottom_md = \"{bottom} m\"\ndiameter = \"{id:.3} in\"\ncased = true\nfriction = {mu_surface:.3}\n"
            ));
        }
        t.push_str(&format!(
            "[[hole]]\nbottom_md = \"{shoe} m\"\ndiameter = \"{} in\"\ncased = true\nfriction = {mu_cased:.3}\n",
            size.casing_id_in
        ));
        t.push_str(&format!(
            "[[hole]]\nbottom_md = \"{total_md} m\"\ndiameter = \"{:.3} in\"\nfriction = {mu_open:.3}\n",
            size.hole_in * washout
        ));
        t.push_str(&format!("[mud]\ndensity = \"{sg:.3} sg\"\n"));
        for c in &comps {
            t.push_str(c);
        }
        t.push_str(&format!("[operation]\nmode = \"{op_mode}\"\n"));
        if turning {
            t.push_str(&format!("rpm = \"{rpm} rpm\"\n"));
        }
        if moving {
            t.push_str(&format!("axial_speed = \"{axial_speed} m/s\"\n"));
        }
        if on_bottom && wob > 0.0 {
            t.push_str(&format!("weight_on_bit = \"{:.3} kN\"\n", wob / 1e3));
            if mode == "drilling" {
                t.push_str(&format!(
                    "torque_on_bit = \"{:.3} kN.m\"\n",
                    0.02 * wob / 1e3 * size.hole_in / 8.5
                ));
            }
        }
        t.push_str(&contact_and_mesh(
            sites,
            wall_stiffness,
            exponent,
            element,
            bha_element,
        ));
        t
    };
    let spec = WellSpec {
        seed,
        trajectory,
        turn,
        total_md,
        max_inclination_deg: max_inc,
        hole_in: size.hole_in,
        mode: mode.to_string(),
        wob_n: 0.0,
        element_m: element,
        bha_element_m: bha_element,
        stabilizers,
        bend_deg: bend,
        sites: sites.to_string(),
        wall_stiffness,
        exponent,
    };
    let cap = if size.hole_in < 7.0 { 60e3 } else { 150e3 };
    let wob_of = |limit: f64| ((wob_fraction * limit).min(cap) / 100.0).round() * 100.0;
    write_at_wob(dir.join(format!("{name}.toml")), spec, &case_text, &wob_of)
}
