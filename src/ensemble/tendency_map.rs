//! The tendency map (issue 25): the assembly's build and turn rates over a grid a BHA
//! engineer chooses a layout from — stab1's distance from the bit × weight on bit for a
//! rotary assembly (pendulum, packed, fulcrum), toolface × weight on bit for one with a bent
//! housing or bent sub (the motor's yield when sliding), weight on bit alone for a slick
//! assembly. Each cell is one [`crate::bha::tendency::tendency`] of the case's model with
//! the stabilizer moved as the ensemble's `stab1.from_bit` key moves it.

use rayon::prelude::*;
use serde::Serialize;

use crate::bha::tendency::{tendency, Tendency};
use crate::case::Case;

/// What the map's first axis varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MapAxis {
    /// stab1's distance from the bit (m).
    Stab1FromBit,
    /// Every bend's toolface from the high side (rad).
    Toolface,
    /// Nothing: a slick assembly, weight on bit only.
    None,
}

impl MapAxis {
    /// The axis's column name in `tendency_map.csv`.
    pub fn column(self) -> &'static str {
        match self {
            MapAxis::Stab1FromBit => "stab1_from_bit_m",
            MapAxis::Toolface => "toolface_deg",
            MapAxis::None => "none",
        }
    }
}

/// One cell of the map.
#[derive(Clone, Debug, Serialize)]
pub struct MapCell {
    /// The axis value as written in the CSV: stab1's distance from the bit where its site
    /// went (the node nearest the one asked; m), or the toolface (degrees).
    pub x: f64,
    /// Weight on bit (N).
    pub weight_on_bit_n: f64,
    /// Its tendency.
    pub tendency: Tendency,
}

/// The map's grid of a case: the axis, its values (SI) and the weights on bit — from the
/// case's `[tendency]` table, or the defaults ([`crate::case::TendencySpec`]).
pub fn map_grid(case: &Case) -> (MapAxis, Vec<f64>, Vec<f64>) {
    let model = &case.model;
    let t = &case.tendency;
    let base = if model.weight_on_bit > 0.0 {
        model.weight_on_bit
    } else {
        50e3
    };
    let wob = if t.weight_on_bit.is_empty() {
        [0.25, 0.5, 1.0, 1.5, 2.0].map(|f| f * base).to_vec()
    } else {
        t.weight_on_bit.clone()
    };
    if !model.bends.is_empty() {
        let tf = if t.toolface.is_empty() {
            (0..12).map(|k| (30.0 * k as f64).to_radians()).collect()
        } else {
            t.toolface.clone()
        };
        return (MapAxis::Toolface, tf, wob);
    }
    if model.stabilizer_sites().is_empty() {
        return (MapAxis::None, vec![0.0], wob);
    }
    let positions = if t.from_bit.is_empty() {
        let hi = (case.bha_length - 1.0).clamp(2.0, 40.0);
        (0..12)
            .map(|k| 1.0 + (hi - 1.0) * k as f64 / 11.0)
            .collect()
    } else {
        t.from_bit.clone()
    };
    (MapAxis::Stab1FromBit, positions, wob)
}

/// Computes the map (rayon over cells; `progress` is called once per cell done). A cell
/// whose model cannot be built (a stabilizer position outside the string) carries the
/// reason in its notes.
/// `settings` is the case's bit–rock model with the run's deadline, if any.
pub fn tendency_map(
    case: &Case,
    settings: &crate::bha::tendency::TendencySettings,
    progress: &(dyn Fn() + Sync),
) -> (MapAxis, Vec<MapCell>) {
    let (axis, xs, wobs) = map_grid(case);
    // Stabilizer positions stand where asked: the mesh takes a node at each (the case's
    // own mesh where that cannot be built; each cell then says the distance it got).
    let key = crate::keys::Key::parse("stab1.from_bit").expect("stab1.from_bit is a key");
    let at = |x: f64| crate::ensemble::Variant {
        name: String::new(),
        overrides: vec![(key.clone(), crate::keys::Value::Number(x))],
    };
    let placed = match axis {
        MapAxis::Stab1FromBit => {
            let cells: Vec<_> = xs.iter().map(|&x| at(x)).collect();
            crate::ensemble::placed_case(case, &cells).ok().flatten()
        }
        _ => None,
    };
    let case = placed.as_ref().unwrap_or(case);
    let cells: Vec<(f64, f64)> = xs
        .iter()
        .flat_map(|&x| wobs.iter().map(move |&w| (x, w)))
        .collect();
    let settings = *settings;
    let out = cells
        .par_iter()
        .map(|&(x, w)| {
            let (model, toolface, shown) = match axis {
                MapAxis::Stab1FromBit => {
                    // The distance the stabilizer got: its site's node nearest the asked.
                    let model = crate::ensemble::apply(case, &at(x));
                    let got = model.as_ref().map_or(x, |m| {
                        let site = m.stabilizer_sites()[0];
                        let bit = m.nodes[m.nodes.len() - 1].md;
                        bit - m.nodes[m.sites[site].node].md
                    });
                    (model, None, got)
                }
                // The motor's yield: sliding (the bend held at the toolface).
                MapAxis::Toolface => (
                    Ok(crate::model::Model {
                        rotation_speed: 0.0,
                        ..case.model.clone()
                    }),
                    Some(x),
                    x.to_degrees(),
                ),
                MapAxis::None => (Ok(case.model.clone()), None, x),
            };
            let t = match model {
                Ok(m) => tendency(&m, case.bha_length, w, toolface, &settings),
                Err(e) => Tendency {
                    notes: vec![e.to_string()],
                    settings,
                    ..Default::default()
                },
            };
            progress();
            MapCell {
                x: shown,
                weight_on_bit_n: w,
                tendency: t,
            }
        })
        .collect();
    (axis, out)
}
