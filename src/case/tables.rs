//! The readers of `[[hole]]`, `[[string]]`, `[operation]` and `[contact]`.

use super::*;
use crate::keys::Param;

/// What `[[string]]` gives: the tubulars from the bit up, each stabilizer's blade
/// diameter, each component's centre-of-mass offset, and the kinks of bent subs/housings
/// (MD above the bit, angle, toolface, and the key's span for messages).
pub(super) struct StringRead {
    pub(super) tubulars: Vec<Tubular>,
    pub(super) blades: Vec<Option<f64>>,
    /// Per component: tool joints (OD, length, spacing; m).
    pub(super) tool_joints: Vec<Option<(f64, f64, f64)>>,
    /// Per component: grade and wear, where given.
    pub(super) strength: Vec<Option<crate::strength::PipeStrength>>,
    pub(super) eccentricities: Vec<f64>,
    pub(super) bends: Vec<(f64, f64, f64, std::ops::Range<usize>)>,
    /// What the reader noticed and a user should see (components above the surface).
    pub(super) warnings: Vec<String>,
}

/// `[[string]]`: the components from the bit up, read and checked against the hole
/// (`elements`: the drill-pipe and BHA element lengths).
pub(super) fn read_string(
    ctx: &Ctx,
    spec: &CaseSpec,
    hole: &[HoleSection],
    bit_md: f64,
    elements: (f64, f64),
) -> Result<StringRead, InputError> {
    let (el_pipe, el_bha) = elements;
    let pos = |x: f64| x > 0.0;
    let hole_at = |md: f64| hole_section_at(hole, md);
    // String, from the bit up.
    if spec.string.is_empty() {
        return Err(InputError {
            source_name: ctx.path.display().to_string(),
            line: 1,
            key: "string".into(),
            message: "at least one [[string]] component is required".into(),
        });
    }
    let mut tubulars = Vec::new();
    let mut blades = Vec::new();
    let mut tool_joints = Vec::new();
    let mut strength = Vec::new();
    let mut eccentricities: Vec<f64> = Vec::new();
    let mut bends = Vec::new();
    for (k, c) in spec.string.iter().enumerate() {
        let kind = c.kind.get_ref().clone();
        if kind == "bit" && k > 0 {
            // Listed from the top down, the string would be meshed upside down (the
            // pipe at the bit) and give a plausible-looking, wrong answer.
            return Err(ctx.err(
                c.kind.span(),
                "string.kind",
                format!(
                    "\"bit\" is component {} of the [[string]] list, which runs from the bit \
                     up: the bit must be the first component",
                    k + 1
                ),
            ));
        }
        let length = ctx.quantity(&c.length, "string.length", Dimension::Length, pos, "> 0")?;
        let od = ctx.quantity(
            &c.od,
            "string.od",
            Dimension::Length,
            |x| x > 0.0 && x < 1.0,
            "0 < od < 1 m",
        )?;
        let id = ctx.quantity(
            &c.id,
            "string.id",
            Dimension::Length,
            |x| (0.0..od).contains(&x),
            &format!("0 ≤ id < od ({od} m)"),
        )?;
        let e = match &c.youngs_modulus {
            Some(q) => ctx.quantity(
                q,
                "string.youngs_modulus",
                Dimension::Pressure,
                |x| x > 1e9 && x < 1e12,
                "1 GPa … 1000 GPa",
            )?,
            None => 207e9,
        };
        let nu = match &c.poisson_ratio {
            Some(q) => ctx.number(
                q,
                "string.poisson_ratio",
                |x| (0.0..0.5).contains(&x),
                "0 ≤ ν < 0.5",
            )?,
            None => 0.3,
        };
        let rho = match &c.density {
            Some(q) => ctx.quantity(
                q,
                "string.density",
                Dimension::Density,
                |x| x > 1000.0 && x < 20000.0,
                "1000 … 20000 kg/m3",
            )?,
            None => 7850.0,
        };
        let eccentricity = match (&c.mass_eccentricity, &c.imbalance) {
            (Some(_), Some(q)) => {
                return Err(ctx.err(
                    q.span(),
                    "string.imbalance",
                    "give mass_eccentricity or imbalance, not both",
                ))
            }
            (Some(q), None) => ctx.quantity(
                q,
                "string.mass_eccentricity",
                Dimension::Length,
                |x| (0.0..=0.5 * od).contains(&x),
                &format!("0 ≤ offset ≤ od/2 ({} m)", crate::units::show(0.5 * od)),
            )?,
            (None, Some(q)) => {
                let mass = rho * std::f64::consts::FRAC_PI_4 * (od * od - id * id) * length;
                ctx.quantity(
                    q,
                    "string.imbalance",
                    Dimension::MassLength,
                    |x| (0.0..=0.5 * od * mass).contains(&x),
                    &format!(
                        "0 ≤ imbalance ≤ the component's mass × od/2 ({} kg·m)",
                        crate::units::show(0.5 * od * mass)
                    ),
                )? / mass
            }
            (None, None) => 0.0,
        };
        eccentricities.push(eccentricity);
        let bend = match &c.bend {
            Some(q) => {
                let angle = ctx.angle(q, "string.bend", |x| (0.0..=5.0).contains(&x), "0 … 5°")?;
                let at = match &c.bend_from_bottom {
                    Some(b) => ctx.quantity(
                        b,
                        "string.bend_from_bottom",
                        Dimension::Length,
                        |x| x > 0.0 && x < length,
                        &format!(
                            "0 < bend_from_bottom < the component's length ({} m)",
                            crate::units::show(length)
                        ),
                    )?,
                    None => 0.5 * length,
                };
                let toolface = match &c.bend_toolface {
                    Some(t) => ctx.angle(
                        t,
                        "string.bend_toolface",
                        |x| (-360.0..=360.0).contains(&x),
                        "-360 … 360°",
                    )?,
                    None => 0.0,
                };
                let above_bit = tubulars.iter().map(|t: &Tubular| t.length).sum::<f64>() + at;
                Some((
                    above_bit,
                    angle.to_radians(),
                    toolface.to_radians(),
                    q.span(),
                ))
            }
            None => {
                for (k, v) in [
                    ("string.bend_from_bottom", &c.bend_from_bottom),
                    ("string.bend_toolface", &c.bend_toolface),
                ] {
                    if let Some(v) = v {
                        return Err(ctx.err(v.span(), k, "needs string.bend (the bend angle)"));
                    }
                }
                None
            }
        };
        bends.extend(bend);
        let blade = match &c.blade_diameter {
            Some(q) => {
                let md_here = bit_md - tubulars.iter().map(|t: &Tubular| t.length).sum::<f64>();
                let hole_d = hole_at(md_here).diameter;
                Some(ctx.quantity(q, "string.blade_diameter", Dimension::Length, |x| x >= od && x <= hole_d, &format!("od ({} m) ≤ blade diameter ≤ hole diameter ({} m): the disk must fit the hole", crate::units::show(od), crate::units::show(hole_d)))?)
            }
            None => None,
        };
        if od > hole_at(bit_md - tubulars.iter().map(|t: &Tubular| t.length).sum::<f64>()).diameter
        {
            return Err(ctx.err(
                c.od.span(),
                "string.od",
                format!("{} m is wider than the hole", crate::units::show(od)),
            ));
        }
        let bha = kind != "drill_pipe";
        let mut element_length = if bha { el_bha } else { el_pipe };
        let joint = match &c.tool_joint_od {
            None => {
                for (k, v) in [
                    ("string.tool_joint_length", &c.tool_joint_length),
                    ("string.joint_spacing", &c.joint_spacing),
                    (
                        "string.tool_joint_makeup_torque",
                        &c.tool_joint_makeup_torque,
                    ),
                ] {
                    if let Some(v) = v {
                        return Err(ctx.err(v.span(), k, "needs string.tool_joint_od"));
                    }
                }
                None
            }
            Some(q) => {
                let md_here = bit_md - tubulars.iter().map(|t: &Tubular| t.length).sum::<f64>();
                let hole_d = hole_at(md_here).diameter;
                let tj = ctx.quantity(
                    q,
                    "string.tool_joint_od",
                    Dimension::Length,
                    |x| x > od && x < hole_d,
                    &format!(
                        "od ({} m) < tool_joint_od < hole diameter ({} m)",
                        crate::units::show(od),
                        crate::units::show(hole_d)
                    ),
                )?;
                let tj_length = match &c.tool_joint_length {
                    Some(q) => ctx.quantity(
                        q,
                        "string.tool_joint_length",
                        Dimension::Length,
                        |x| x > 0.0 && x <= 2.0,
                        "0 < tool_joint_length ≤ 2 m",
                    )?,
                    None => 0.45,
                };
                let spacing = match &c.joint_spacing {
                    Some(q) => ctx.quantity(
                        q,
                        "string.joint_spacing",
                        Dimension::Length,
                        |x| (3.0..=15.0).contains(&x) && x > tj_length,
                        "3 … 15 m (one joint of pipe), longer than the tool joint",
                    )?,
                    None => 9.144,
                };
                // A node at every joint: the component in whole joints, each in as many
                // elements as the mesh length asks (the last joint takes what is left).
                let joints = (length / spacing).round().max(1.0);
                let per_joint = (spacing / element_length).round().max(1.0);
                element_length = length / (joints * per_joint) * (1.0 + 1e-12);
                Some((tj, tj_length, spacing))
            }
        };
        tool_joints.push(joint);
        // Grade (or yield strength) and wear class.
        let wall = match &c.wear {
            None => 1.0,
            Some(w) => crate::strength::WEAR
                .iter()
                .find(|(n, _)| *n == w.get_ref().as_str())
                .map(|(_, f)| *f)
                .ok_or_else(|| {
                    ctx.err(
                        w.span(),
                        "string.wear",
                        format!(
                            "unknown wear class {:?}; allowed: new, premium, class2",
                            w.get_ref()
                        ),
                    )
                })?,
        };
        let grade = match (&c.grade, &c.yield_strength) {
            (Some(_), Some(q)) => {
                return Err(ctx.err(
                    q.span(),
                    "string.yield_strength",
                    "give grade or yield_strength, not both",
                ))
            }
            (Some(g), None) => Some(
                crate::strength::GRADES
                    .iter()
                    .find(|(n, _)| n.eq_ignore_ascii_case(g.get_ref()))
                    .copied()
                    .ok_or_else(|| {
                        ctx.err(
                            g.span(),
                            "string.grade",
                            format!("unknown grade {:?}; allowed: E75, X95, G105, S135 (or yield_strength)", g.get_ref()),
                        )
                    })?,
            ),
            (None, Some(q)) => Some((
                "custom",
                ctx.quantity(
                    q,
                    "string.yield_strength",
                    Dimension::Pressure,
                    |x| x > 1e8 && x < 3e9,
                    "100 MPa … 3 GPa",
                )?,
            )),
            (None, None) => {
                if let Some(w) = &c.wear {
                    return Err(ctx.err(w.span(), "string.wear", "needs string.grade (or yield_strength)"));
                }
                None
            }
        };
        let makeup = match (&c.tool_joint_makeup_torque, &grade) {
            (None, _) => None,
            (Some(q), None) => {
                return Err(ctx.err(
                    q.span(),
                    "string.tool_joint_makeup_torque",
                    "needs string.grade (or yield_strength): the limit is drawn on the pipe's tension–torque envelope",
                ))
            }
            (Some(q), Some(_)) => Some(ctx.quantity(
                q,
                "string.tool_joint_makeup_torque",
                Dimension::Torque,
                |x| (1e3..=3e5).contains(&x),
                "1 … 300 kN·m (≈ 740 … 221,000 ft·lbf)",
            )?),
        };
        strength.push(grade.map(|(name, y)| {
            crate::strength::PipeStrength::new(name, y, wall, od, id).with_makeup_torque(makeup)
        }));
        blades.push(blade);
        tubulars.push(Tubular {
            name: kind,
            length,
            outer_diameter: od,
            inner_diameter: id,
            youngs_modulus: e,
            poisson_ratio: nu,
            density: rho,
            element_length,
        });
    }
    let string_length: f64 = tubulars.iter().map(|t| t.length).sum();
    if string_length + 1e-9 < bit_md {
        let last = spec.string.last().map(|c| c.length.span()).unwrap_or(0..0);
        return Err(ctx.err(last, "string.length", format!("the string is {} m long, shorter than the bit depth {} m: it must reach the surface", crate::units::show(string_length), crate::units::show(bit_md))));
    }
    Ok(StringRead {
        warnings: above_surface(&tubulars, bit_md).into_iter().collect(),
        tubulars,
        blades,
        tool_joints,
        strength,
        eccentricities,
        bends,
    })
}

/// The warning for components listed above the one that reaches the surface (from the
/// bit at `bit_md`): the mesh leaves them out ([`crate::model::components_in_hole`]), which
/// is what a string list written for a deeper well means, and what a list written from the
/// top down would silently do to its BHA.
fn above_surface(tubulars: &[Tubular], bit_md: f64) -> Option<String> {
    let first = crate::model::components_in_hole(tubulars, bit_md);
    if first == tubulars.len() {
        return None;
    }
    let names: Vec<&str> = tubulars[first..].iter().map(|t| t.name.as_str()).collect();
    Some(format!(
        "[[string]] component{} {} ({}) lie{} above the surface: {} it \
         from the bit at {} m, so the mesh leaves {} out (the list runs from the bit up)",
        if names.len() > 1 { "s" } else { "" },
        if names.len() > 1 {
            format!("{}–{}", first + 1, tubulars.len())
        } else {
            (first + 1).to_string()
        },
        names.join(", "),
        if names.len() > 1 { "" } else { "s" },
        if first > 1 {
            format!("the {first} components below already reach")
        } else {
            "the first component alone reaches".to_string()
        },
        crate::units::show(bit_md),
        if names.len() > 1 { "them" } else { "it" },
    ))
}

/// What `[operation]` sets on the model.
pub(super) struct Operation {
    pub(super) wob: f64,
    pub(super) tob: f64,
    pub(super) hook: Option<f64>,
    pub(super) axial_speed: f64,
    pub(super) rotation_speed: f64,
}

/// `[operation]`: weight and torque on bit, hook load, the mode and its speeds.
pub(super) fn read_operation(ctx: &Ctx, spec: &CaseSpec) -> Result<Operation, InputError> {
    // Operation.
    let op = &spec.operation;
    let wob = op
        .weight_on_bit
        .as_ref()
        .map(|q| {
            let (_, ok, words) = Param::Wob.range();
            ctx.quantity(q, "operation.weight_on_bit", Dimension::Force, ok, words)
        })
        .transpose()?
        .unwrap_or(0.0);
    let tob = op
        .torque_on_bit
        .as_ref()
        .map(|q| {
            let (_, ok, words) = Param::Tob.range();
            ctx.quantity(q, "operation.torque_on_bit", Dimension::Torque, ok, words)
        })
        .transpose()?
        .unwrap_or(0.0);
    let rpm = op
        .rpm
        .as_ref()
        .map(|q| {
            let (_, ok, words) = Param::Rpm.range();
            ctx.quantity(q, "operation.rpm", Dimension::AngularSpeed, ok, words)
        })
        .transpose()?
        .unwrap_or(0.0);
    let speed = op
        .axial_speed
        .as_ref()
        .map(|q| {
            ctx.quantity(
                q,
                "operation.axial_speed",
                Dimension::Speed,
                |x| (0.0..10.0).contains(&x),
                "0 ≤ speed < 10 m/s",
            )
        })
        .transpose()?
        .unwrap_or(0.5);
    let hook = op
        .hook_load
        .as_ref()
        .map(|q| {
            ctx.quantity(
                q,
                "operation.hook_load",
                Dimension::Force,
                |x| x > 0.0,
                "> 0",
            )
        })
        .transpose()?;
    if let (Some(_), Some(w)) = (hook, &op.weight_on_bit) {
        return Err(ctx.err(
            w.span(),
            "operation.weight_on_bit",
            "give either weight_on_bit (top clamped) or hook_load (bit on bottom), not both",
        ));
    }
    let mode = *op.mode.get_ref();
    let rotates = mode.rotates();
    match &op.rpm {
        None if rotates => {
            return Err(ctx.err(
                op.mode.span(),
                "operation.rpm",
                format!(
                    "mode = \"{mode}\" needs the rotary speed: add rpm = \"90 rpm\" (or the \
                     value you rotate at) to [operation]"
                ),
            ))
        }
        Some(q) if rotates && rpm == 0.0 => {
            return Err(ctx.err(
                q.span(),
                "operation.rpm",
                format!(
                    "mode = \"{mode}\" at 0 rpm has no rotation, hence no torque: give the \
                     rotary speed (> 0), or mode = \"sliding\" / \"tripping_in\" / \
                     \"tripping_out\""
                ),
            ))
        }
        Some(q) if !rotates && rpm != 0.0 => {
            return Err(ctx.err(
                q.span(),
                "operation.rpm",
                format!(
                    "mode = \"{mode}\" does not rotate the string, so this rpm would be ignored: \
                     remove rpm, or use mode = \"rotating\""
                ),
            ))
        }
        _ => {}
    }
    // Reaming (running in while rotating) and back-reaming (pulling out while rotating):
    // both speeds, the friction split by the velocity's direction at each contact.
    let axial_speed = mode.axial_direction() * speed;
    let rotation_speed = if rotates { rpm } else { 0.0 };
    Ok(Operation {
        wob,
        tob,
        hook,
        axial_speed,
        rotation_speed,
    })
}

/// `[contact]`: the contact law's settings, the friction model and whether every node is
/// a contact site.
pub(super) fn read_contact(
    ctx: &Ctx,
    spec: &CaseSpec,
) -> Result<(ContactSettings, Option<FrictionModel>, bool), InputError> {
    // Contact.
    let cs = spec.contact.clone();
    let q_or = |q: Option<Q>,
                key: &str,
                dim: Dimension,
                default: f64,
                ok: &dyn Fn(f64) -> bool,
                range: &str|
     -> Result<f64, InputError> {
        match q {
            Some(q) => ctx.quantity(&q, key, dim, ok, range),
            None => Ok(default),
        }
    };
    // The ranges an ensemble's overrides of these keys are checked against too.
    let (_, stiffness_ok, stiffness_words) = Param::WallStiffness.range();
    let (_, exponent_ok, exponent_words) = Param::Exponent.range();
    let (_, damping_ok, damping_words) = Param::WallDamping.range();
    let (_, eps_ok, eps_words) = Param::Eps.range();
    let settings = ContactSettings {
        wall_stiffness: q_or(
            cs.as_ref().and_then(|c| c.wall_stiffness.clone()),
            "contact.wall_stiffness",
            Dimension::Stiffness,
            6e7,
            &stiffness_ok,
            stiffness_words,
        )?,
        spring_exponent: match cs.as_ref().and_then(|c| c.exponent.clone()) {
            Some(q) => ctx.number(&q, "contact.exponent", exponent_ok, exponent_words)?,
            None => 1.0,
        },
        wall_damping: q_or(
            cs.as_ref().and_then(|c| c.damping.clone()),
            "contact.damping",
            Dimension::Damping,
            8e3,
            &damping_ok,
            damping_words,
        )?,
        eps: q_or(
            cs.as_ref().and_then(|c| c.eps.clone()),
            "contact.eps",
            Dimension::Speed,
            1e-3,
            &eps_ok,
            eps_words,
        )?,
        soft_blend: q_or(
            cs.as_ref().and_then(|c| c.soft_blend.clone()),
            "contact.soft_blend",
            Dimension::Length,
            1e-5,
            &|x| x > 0.0,
            "> 0",
        )?,
    };
    // `None`: not given (the case chooses by its operation).
    let friction = match cs.as_ref().and_then(|c| c.friction_model.clone()) {
        None => None,
        Some(s) => match s.get_ref().as_str() {
            "split" => Some(FrictionModel::Split),
            "coupled" => Some(FrictionModel::Coupled),
            other => {
                return Err(ctx.err(
                    s.span(),
                    "contact.friction_model",
                    format!("unknown model {other:?}; allowed: split, coupled"),
                ))
            }
        },
    };
    let all_nodes = match cs.as_ref().and_then(|c| c.sites.clone()) {
        None => false,
        Some(s) => match s.get_ref().as_str() {
            "stabilizers" => false,
            "all_nodes" => true,
            other => {
                return Err(ctx.err(
                    s.span(),
                    "contact.sites",
                    format!("unknown value {other:?}; allowed: stabilizers, all_nodes"),
                ))
            }
        },
    };
    Ok((settings, friction, all_nodes))
}

/// `[[hole]]`: the hole sections from the surface down, each below the one before, the
/// last reaching the bit.
pub(super) fn read_hole(
    ctx: &Ctx,
    spec: &CaseSpec,
    path: &Path,
    bit_md: f64,
) -> Result<Vec<HoleSection>, InputError> {
    // Hole sections.
    let mut hole = Vec::new();
    let mut previous = 0.0;
    for h in &spec.hole {
        let bottom = ctx.quantity(
            &h.bottom_md,
            "hole.bottom_md",
            Dimension::Length,
            |x| x > previous,
            &format!("> the previous section's bottom ({previous} m)"),
        )?;
        let d = ctx.quantity(
            &h.diameter,
            "hole.diameter",
            Dimension::Length,
            |x| x > 0.0 && x < 2.0,
            "0 < diameter < 2 m",
        )?;
        let (_, mu_ok, mu_words) = Param::Mu.range();
        let mu = ctx.number(&h.friction, "hole.friction", mu_ok, mu_words)?;
        hole.push(HoleSection {
            bottom_md: bottom,
            diameter: d,
            friction: mu,
            cased: h.cased,
        });
        previous = bottom;
    }
    if hole.is_empty() {
        return Err(InputError {
            source_name: path.display().to_string(),
            line: 1,
            key: "hole".into(),
            message: "at least one [[hole]] section is required".into(),
        });
    }
    if previous + 1e-9 < bit_md {
        let last = spec.hole.last().map(|h| h.bottom_md.span()).unwrap_or(0..0);
        return Err(ctx.err(
            last,
            "hole.bottom_md",
            format!(
                "the last hole section ends at {} m, above the bit at {} m",
                crate::units::show(previous),
                crate::units::show(bit_md)
            ),
        ));
    }
    Ok(hole)
}
