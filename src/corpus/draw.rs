//! The drawing helpers both corpus styles share ([`super::write_well`],
//! [`super::user::write_user_well`]; [`super::dynamic`]): survey stations with dogleg noise,
//! weighted picks, the survey CSV, a `[[string]]` table.

use std::path::Path;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::Trajectory;
use crate::error::Error;

/// Survey stations (md, inclination, azimuth; deg) every 30 m of a trajectory with noise.
pub(super) fn survey(
    rng: &mut ChaCha8Rng,
    kind: Trajectory,
    total_md: f64,
) -> (Vec<[f64; 3]>, bool) {
    // Piecewise plan: (md where a rate starts, inclination rate °/30 m, target inclination).
    let azimuth0 = rng.random_range(0.0..360.0);
    let kop = match kind {
        Trajectory::Vertical => total_md,
        Trajectory::Horizontal => rng.random_range(0.15..0.45) * total_md,
        _ => rng.random_range(0.1..0.5) * total_md,
    };
    let build = match kind {
        Trajectory::Horizontal => rng.random_range(3.0..8.0),
        _ => rng.random_range(1.0..4.0),
    };
    let hold_inc = match kind {
        Trajectory::Vertical => 0.0,
        Trajectory::BuildAndHold => rng.random_range(15.0..70.0),
        Trajectory::SShaped => rng.random_range(20.0..45.0),
        Trajectory::Horizontal => rng.random_range(86.0..92.0),
    };
    let drop_at = kop
        + 30.0 * hold_inc / build
        + rng.random_range(0.1..0.4) * (total_md - kop - 30.0 * hold_inc / build).max(0.0);
    let drop = rng.random_range(1.0..3.0);
    let final_inc = rng.random_range(0.0..10.0);
    let turn = kind != Trajectory::Vertical && rng.random_bool(0.4);
    let (turn_from, turn_to, turn_rate) = if turn {
        let a = rng.random_range(kop..total_md);
        let b = rng.random_range(a..total_md);
        let rate = rng.random_range(0.5..3.0) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        (a, b, rate)
    } else {
        (0.0, 0.0, 0.0)
    };
    let sigma = rng.random_range(0.05..0.4);
    let mut out = Vec::new();
    let (mut inc, mut az) = (0.0f64, azimuth0);
    let mut md = 0.0;
    let noise = |rng: &mut ChaCha8Rng| {
        // Box–Muller: normal noise without another crate.
        let u1: f64 = rng.random_range(1e-12..1.0);
        let u2: f64 = rng.random();
        sigma * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    };
    loop {
        let (ni, na) = (noise(rng), noise(rng));
        let inc_out = if inc < 1e-9 {
            ni.abs()
        } else {
            (inc + ni).clamp(0.0, 179.0)
        };
        let az_noise = na / (inc_out.to_radians().sin()).max(0.1);
        out.push([md, inc_out, (az + az_noise).rem_euclid(360.0)]);
        if md >= total_md {
            break;
        }
        let next = (md + 30.0).min(total_md + 30.0);
        // Inclination plan at the next station.
        if next > kop {
            if kind == Trajectory::SShaped && next > drop_at {
                inc = (inc - drop).max(final_inc);
            } else {
                inc = (inc + build).min(hold_inc);
            }
        }
        if turn && next > turn_from && next <= turn_to {
            az += turn_rate;
        }
        md = next;
    }
    (out, turn)
}

pub(super) fn pick<T: Copy>(rng: &mut ChaCha8Rng, items: &[(T, f64)]) -> T {
    let total: f64 = items.iter().map(|x| x.1).sum();
    let mut r = rng.random_range(0.0..total);
    for &(x, w) in items {
        if r < w {
            return x;
        }
        r -= w;
    }
    items[items.len() - 1].0
}

/// Writes `stations` (MD, inclination, azimuth; m, deg) as the survey CSV `<name>.csv` in
/// `dir` (created), as a user's survey is written; returns the file's name.
pub(super) fn write_survey(dir: &Path, name: &str, stations: &[[f64; 3]]) -> Result<String, Error> {
    let csv_name = format!("{name}.csv");
    let mut csv = String::from("md_m, inclination_deg, azimuth_deg\n");
    for s in stations {
        csv.push_str(&format!("{:.2}, {:.4}, {:.4}\n", s[0], s[1], s[2]));
    }
    std::fs::create_dir_all(dir)
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", dir.display())))?;
    std::fs::write(dir.join(&csv_name), csv)?;
    Ok(csv_name)
}

/// A `[[string]]` table of a tube `len` m long, `od` × `id` in, with `extra` lines.
pub(super) fn tube(kind: &str, len: f64, od: f64, id: f64, extra: &str) -> String {
    format!(
        "[[string]]\nkind = \"{kind}\"\nlength = \"{len} m\"\nod = \"{od} in\"\nid = \"{id} in\"\n{extra}"
    )
}

/// A corpus case's `[contact]` and `[mesh]` tables (both styles write them alike).
pub(super) fn contact_and_mesh(
    sites: &str,
    wall_stiffness: f64,
    exponent: f64,
    element: f64,
    bha_element: f64,
) -> String {
    format!(
        "[contact]\nsites = \"{sites}\"\nwall_stiffness = {wall_stiffness:.6e}\nexponent = {exponent:.6}\n\
         [mesh]\nelement_length = \"{element} m\"\nbha_element_length = \"{bha_element} m\"\n"
    )
}
