//! The readers of `[dynamics]` and `[ensemble]` (with its uncertain inputs).

use super::*;
use crate::uq::distribution::DistributionError;

pub(super) fn ensemble_settings(
    ctx: &Ctx,
    e: &EnsembleSpec,
    has_dynamics: bool,
) -> Result<EnsembleSettings, InputError> {
    let analysis = match &e.analysis {
        None => Analysis::Static,
        Some(a) => match a.get_ref().as_str() {
            "static" => Analysis::Static,
            "dynamic" if has_dynamics => Analysis::Dynamic,
            "dynamic" => {
                return Err(ctx.err(
                    a.span(),
                    "ensemble.analysis",
                    "\"dynamic\" needs a [dynamics] table",
                ))
            }
            other => {
                return Err(ctx.err(
                    a.span(),
                    "ensemble.analysis",
                    format!("unknown analysis {other:?}; allowed: static, dynamic"),
                ))
            }
        },
    };
    let mut grid = Vec::new();
    // In the order written (the first key varies slowest), not the map's alphabetical one.
    let mut written: Vec<_> = e.grid.iter().flatten().collect();
    written.sort_by_key(|(_, v)| v.span().start);
    for (name, values) in written {
        let key_name = format!("ensemble.grid.{name}");
        let key = crate::keys::Key::parse(name)
            .map_err(|m| ctx.err(values.span(), &key_name, m.to_string()))?;
        if values.get_ref().is_empty() {
            return Err(ctx.err(values.span(), &key_name, "no values"));
        }
        let mut list = Vec::new();
        for q in values.get_ref() {
            list.push(
                key_value(&key, q).map_err(|m| ctx.err(values.span(), &key_name, m.to_string()))?,
            );
        }
        grid.push((key, list));
    }
    let mut uncertain = Vec::new();
    // In the order written: input k takes the sampler's dimension k.
    let mut written: Vec<_> = e.uncertain.iter().flatten().collect();
    written.sort_by_key(|(_, v)| v.span().start);
    for (name, spec) in written {
        let key_name = format!("ensemble.uncertain.{name}");
        let err = |m: String| ctx.err(spec.span(), &key_name, m);
        let key = crate::keys::Key::parse(name).map_err(|m| err(m.to_string()))?;
        uncertain.push((
            key.clone(),
            uncertain_distribution(&key, spec.get_ref()).map_err(|m| err(m.to_string()))?,
        ));
    }
    let correlation = match &e.correlation {
        None => None,
        Some(pairs) => {
            let err = |m: String| ctx.err(pairs.span(), "ensemble.correlation", m);
            let d = uncertain.len();
            let mut c = nalgebra::DMatrix::identity(d, d);
            let index = |name: &str| {
                uncertain
                    .iter()
                    .position(|(k, _)| k.name == name)
                    .ok_or_else(|| err(format!("{name:?} is not in [ensemble.uncertain]")))
            };
            for (a, b, rho) in pairs.get_ref() {
                let (i, j) = (index(a)?, index(b)?);
                if i == j {
                    return Err(err(format!("{a:?} with itself")));
                }
                if !(rho.is_finite() && rho.abs() < 1.0) {
                    return Err(err(format!("{a} with {b}: {rho} is outside (−1, 1)")));
                }
                c[(i, j)] = *rho;
                c[(j, i)] = *rho;
            }
            if c.clone().cholesky().is_none() {
                return Err(err(
                    "the correlations are inconsistent (the matrix is not positive definite)"
                        .into(),
                ));
            }
            Some(c)
        }
    };
    let mut layouts = Vec::new();
    if let Some(list) = &e.layouts {
        for (n, layout) in list.get_ref().iter().enumerate() {
            let key_name = format!("ensemble.layouts[{}]", n + 1);
            let err = |m: String| ctx.err(list.span(), &key_name, m);
            let mut set = Vec::new();
            for (name, q) in layout {
                let key = crate::keys::Key::parse(name).map_err(|m| err(m.to_string()))?;
                if !matches!(
                    key.param,
                    crate::keys::Param::FromBit | crate::keys::Param::Blade
                ) {
                    return Err(err(format!(
                        "{name}: a layout sets stabK.from_bit and stabK.blade only"
                    )));
                }
                set.push((
                    key.clone(),
                    key_value(&key, q).map_err(|m| err(format!("{name}: {m}")))?,
                ));
            }
            if set.is_empty() {
                return Err(err("an empty layout".into()));
            }
            layouts.push(set);
        }
    }
    Ok(EnsembleSettings {
        analysis,
        grid,
        series: e.series.clone().unwrap_or_default(),
        uncertain,
        correlation,
        layouts,
    })
}

/// The value of `q` for `key`: a bare number as a case file writes it
/// ([`crate::keys::Key::number`]), a quantity with its unit or a mode's name
/// ([`crate::keys::Key::value`]).
fn key_value(
    key: &crate::keys::Key,
    q: &Quantity,
) -> Result<crate::keys::Value, crate::keys::KeyError> {
    match q {
        Quantity::Number(x) => key.number(*x),
        Quantity::Text(t) => key.value(t),
        Quantity::Si(x) => key.si(*x),
    }
}

/// The distribution of `[ensemble.uncertain]` entry `u` of key `key`; every value given is
/// parsed and range-checked as the key's own values (a mode's values are their codes).
pub(super) fn uncertain_distribution(
    key: &crate::keys::Key,
    u: &UncertainSpec,
) -> Result<crate::uq::Distribution, DistributionError> {
    use crate::uq::Distribution;
    let value =
        |q: &Option<Quantity>, field: &'static str| -> Result<Option<f64>, DistributionError> {
            q.as_ref()
                .map(|q| {
                    key_value(key, q)
                        .map(|v| v.si())
                        .map_err(|source| DistributionError::Value { field, source })
                })
                .transpose()
        };
    let dist = u.dist.as_str();
    let need = |x: Option<f64>, field: &'static str| {
        x.ok_or_else(|| DistributionError::Needs {
            dist: dist.to_string(),
            field,
        })
    };
    enum Law {
        Uniform,
        Normal,
        LogNormal,
        Triangular,
        Discrete,
    }
    // The parameters each distribution takes; any other given is refused.
    let (law, takes): (Law, &[&str]) = match dist {
        "uniform" => (Law::Uniform, &["min", "max"]),
        "normal" => (Law::Normal, &["mean", "sd", "min", "max"]),
        "lognormal" => (Law::LogNormal, &["median", "sigma"]),
        "triangular" => (Law::Triangular, &["min", "mode", "max"]),
        "discrete" => (Law::Discrete, &["values", "weights"]),
        other => return Err(DistributionError::Unknown(other.to_string())),
    };
    let given = [
        ("min", u.min.is_some()),
        ("max", u.max.is_some()),
        ("mean", u.mean.is_some()),
        ("sd", u.sd.is_some()),
        ("median", u.median.is_some()),
        ("sigma", u.sigma.is_some()),
        ("mode", u.mode.is_some()),
        ("values", u.values.is_some()),
        ("weights", u.weights.is_some()),
    ];
    if let Some((field, _)) = given.iter().find(|(f, g)| *g && !takes.contains(f)) {
        return Err(DistributionError::TakesNo {
            dist: dist.to_string(),
            field,
        });
    }
    let (min, max) = (value(&u.min, "min")?, value(&u.max, "max")?);
    let d = match law {
        Law::Uniform => Distribution::Uniform {
            min: need(min, "min")?,
            max: need(max, "max")?,
        },
        Law::Normal => {
            let sd = match &u.sd {
                // A spread: the key's unit, but not its range (σ of a friction factor
                // may be 0.05, of a WOB 7 kN).
                Some(Quantity::Number(x) | Quantity::Si(x)) => *x,
                Some(q @ Quantity::Text(t)) => match t.trim().parse::<f64>() {
                    Ok(x) => x,
                    Err(_) => key_value(key, q)
                        .map_err(|source| DistributionError::Value {
                            field: "sd",
                            source,
                        })?
                        .si(),
                },
                None => need(None, "sd")?,
            };
            Distribution::Normal {
                mean: need(value(&u.mean, "mean")?, "mean")?,
                sd,
                min: min.unwrap_or(f64::NEG_INFINITY),
                max: max.unwrap_or(f64::INFINITY),
            }
        }
        Law::LogNormal => Distribution::LogNormal {
            median: need(value(&u.median, "median")?, "median")?,
            sigma: need(u.sigma, "sigma (of the logarithm)")?,
        },
        Law::Triangular => Distribution::Triangular {
            min: need(min, "min")?,
            mode: need(value(&u.mode, "mode")?, "mode")?,
            max: need(max, "max")?,
        },
        Law::Discrete => {
            let values = match &u.values {
                None => {
                    return Err(DistributionError::Needs {
                        dist: dist.to_string(),
                        field: "values",
                    })
                }
                Some(list) => list
                    .iter()
                    .map(|q| {
                        key_value(key, q).map(|v| v.si()).map_err(|source| {
                            DistributionError::Value {
                                field: "values",
                                source,
                            }
                        })
                    })
                    .collect::<Result<Vec<f64>, _>>()?,
            };
            let weights = u.weights.clone().unwrap_or_else(|| vec![1.0; values.len()]);
            Distribution::Discrete { values, weights }
        }
    };
    d.check()?;
    Ok(d)
}

pub(super) fn dynamics_settings(
    ctx: &Ctx,
    d: &DynamicsSpec,
) -> Result<DynamicsSettings, InputError> {
    let duration = ctx.quantity(
        &d.duration,
        "dynamics.duration",
        Dimension::Time,
        |x| x > 0.0 && x <= 1e5,
        "0 < duration ≤ 1e5 s",
    )?;
    let opt = |q: &Option<Q>,
               key: &str,
               default: f64,
               ok: &dyn Fn(f64) -> bool,
               range: &str|
     -> Result<f64, InputError> {
        match q {
            Some(q) => ctx.quantity(q, key, Dimension::Time, ok, range),
            None => Ok(default),
        }
    };
    let time_step = opt(
        &d.time_step,
        "dynamics.time_step",
        1e-3,
        &|x| x > 0.0 && x <= duration,
        "0 < time_step ≤ duration",
    )?;
    let output_interval = opt(
        &d.output_interval,
        "dynamics.output_interval",
        1e-2_f64.max(time_step),
        &|x| x >= time_step && x <= duration,
        "time_step ≤ interval ≤ duration",
    )?;
    let ramp_time = opt(
        &d.ramp_time,
        "dynamics.ramp_time",
        0.0,
        &|x| x >= 0.0,
        "≥ 0",
    )?;
    let rho_inf = match &d.rho_inf {
        Some(q) => ctx.number(
            q,
            "dynamics.rho_inf",
            |x| (0.0..=1.0).contains(&x),
            "0 ≤ ρ∞ ≤ 1",
        )?,
        None => 0.8,
    };
    let a0 = match &d.rayleigh_mass {
        Some(q) => ctx.number(q, "dynamics.rayleigh_mass", |x| x >= 0.0, "≥ 0 (1/s)")?,
        None => 0.0,
    };
    let a1 = match &d.rayleigh_stiffness {
        Some(q) => ctx.number(q, "dynamics.rayleigh_stiffness", |x| x >= 0.0, "≥ 0 (s)")?,
        None => 0.0,
    };
    let outputs = match &d.outputs {
        None => DYNAMIC_OUTPUTS.iter().map(|s| s.to_string()).collect(),
        Some(list) => {
            let mut out = Vec::new();
            for o in list {
                if !DYNAMIC_OUTPUTS.contains(&o.get_ref().as_str()) {
                    return Err(ctx.err(
                        o.span(),
                        "dynamics.outputs",
                        format!(
                            "unknown output {:?}; allowed: {}",
                            o.get_ref(),
                            DYNAMIC_OUTPUTS.join(", ")
                        ),
                    ));
                }
                out.push(o.get_ref().clone());
            }
            out
        }
    };
    let mass = match &d.mass {
        None => crate::physics::mass::MassKind::Lumped,
        Some(m) => match m.get_ref().as_str() {
            "lumped" => crate::physics::mass::MassKind::Lumped,
            "consistent" => crate::physics::mass::MassKind::Consistent,
            other => {
                return Err(ctx.err(
                    m.span(),
                    "dynamics.mass",
                    format!("unknown mass {other:?}; allowed: lumped, consistent"),
                ))
            }
        },
    };
    let rop = match &d.rop {
        Some(q) => ctx.quantity(
            q,
            "dynamics.rop",
            Dimension::Speed,
            |x| (0.0..=0.1).contains(&x),
            "0 ≤ rop ≤ 0.1 m/s (360 m/h)",
        )?,
        None => 0.0,
    };
    let initial_lateral_velocity = match &d.initial_lateral_velocity {
        Some(q) => ctx.quantity(
            q,
            "dynamics.initial_lateral_velocity",
            Dimension::Speed,
            |x| (0.0..=10.0).contains(&x),
            "0 ≤ speed ≤ 10 m/s",
        )?,
        None => 0.0,
    };
    let initial_lateral_offset = match &d.initial_lateral_offset {
        Some(q) => ctx.quantity(
            q,
            "dynamics.initial_lateral_offset",
            Dimension::Length,
            |x| (0.0..=0.5).contains(&x),
            "0 ≤ offset ≤ 0.5 m (and within the BHA's clearance)",
        )?,
        None => 0.0,
    };
    Ok(DynamicsSettings {
        duration,
        time_step,
        output_interval,
        ramp_time,
        rho_inf,
        rayleigh: (a0, a1),
        outputs,
        mass,
        rop,
        initial_lateral_velocity,
        initial_lateral_offset,
    })
}

/// `[tendency]` checked; `None`: the defaults.
pub(super) fn tendency_settings(
    ctx: &Ctx,
    t: Option<&TendencySpec>,
) -> Result<TendencyCase, InputError> {
    let mut out = TendencyCase {
        settings: crate::bha::tendency::TendencySettings::default(),
        from_bit: vec![],
        weight_on_bit: vec![],
        toolface: vec![],
    };
    let Some(t) = t else {
        return Ok(out);
    };
    let s = &mut out.settings;
    if let Some(x) = &t.side_cutting_index {
        s.side_cutting_index = ctx.number(
            x,
            "tendency.side_cutting_index",
            |v| (0.0..=1.0).contains(&v),
            "0 ≤ side_cutting_index ≤ 1",
        )?;
    }
    if let Some(x) = &t.formation_anisotropy {
        s.formation_anisotropy = ctx.number(
            x,
            "tendency.formation_anisotropy",
            |v| (-0.5..=0.5).contains(&v),
            "−0.5 ≤ formation_anisotropy ≤ 0.5",
        )?;
    }
    if let Some(q) = &t.dip {
        s.dip_deg = ctx.angle(q, "tendency.dip", |v| (0.0..=90.0).contains(&v), "0…90°")?;
    }
    if let Some(q) = &t.dip_azimuth {
        s.dip_azimuth_deg = ctx.angle(
            q,
            "tendency.dip_azimuth",
            |v| (0.0..=360.0).contains(&v),
            "0…360°",
        )?;
    }
    // A list of quantities: each parsed and range-checked, the list's line in errors.
    let list = |l: &Option<Spanned<Vec<Quantity>>>,
                key: &str,
                parse: &dyn Fn(&str) -> Result<f64, crate::units::UnitError>,
                ok: &dyn Fn(f64) -> bool,
                range: &str|
     -> Result<Vec<f64>, InputError> {
        let Some(l) = l else { return Ok(vec![]) };
        if l.get_ref().is_empty() || l.get_ref().len() > 200 {
            return Err(ctx.err(l.span(), key, "give 1 to 200 values"));
        }
        l.get_ref()
            .iter()
            .map(|q| {
                let text = match q {
                    Quantity::Number(x) | Quantity::Si(x) => x.to_string(),
                    Quantity::Text(t) => t.clone(),
                };
                let v = parse(&text)
                    .map_err(|e| ctx.err(l.span(), key, format!("{e}; allowed: {range}")))?;
                if v.is_finite() && ok(v) {
                    Ok(v)
                } else {
                    Err(ctx.err(
                        l.span(),
                        key,
                        format!("{text} is out of range; allowed: {range}"),
                    ))
                }
            })
            .collect()
    };
    out.from_bit = list(
        &t.from_bit,
        "tendency.from_bit",
        &|x| parse_quantity(x, Dimension::Length),
        &|v| v > 0.0 && v <= 200.0,
        "0 < from_bit ≤ 200 m",
    )?;
    out.weight_on_bit = list(
        &t.weight_on_bit,
        "tendency.weight_on_bit",
        &|x| parse_quantity(x, Dimension::Force),
        &|v| (0.0..=5e6).contains(&v),
        "0 ≤ weight_on_bit ≤ 5 MN",
    )?;
    out.toolface = list(
        &t.toolface,
        "tendency.toolface",
        &|x| crate::units::parse_angle_deg(x).map(f64::to_radians),
        &|v| (0.0..=std::f64::consts::TAU).contains(&v),
        "0…360°",
    )?;
    Ok(out)
}

/// `[rig]` ([`crate::rig`]); `None` when absent.
pub(super) fn rig_settings(
    ctx: &Ctx,
    r: Option<&RigSpec>,
) -> Result<Option<crate::rig::Rig>, InputError> {
    let Some(r) = r else { return Ok(None) };
    let mut rig = crate::rig::Rig::default();
    if let Some(q) = &r.block_weight {
        rig.block_weight_n = ctx.quantity(
            q,
            "rig.block_weight",
            Dimension::Force,
            |x| (0.0..=5e6).contains(&x),
            "0 ≤ block_weight ≤ 5 MN",
        )?;
    }
    if let Some(x) = &r.lines {
        rig.lines = ctx.number(
            x,
            "rig.lines",
            |v| v.fract() == 0.0 && (2.0..=16.0).contains(&v) && (v as u32).is_multiple_of(2),
            "an even whole number, 2 … 16",
        )? as u32;
    }
    if let Some(x) = &r.sheave_efficiency {
        rig.sheave_efficiency = ctx.number(
            x,
            "rig.sheave_efficiency",
            |v| (0.9..=1.0).contains(&v),
            "0.9 ≤ sheave_efficiency ≤ 1",
        )?;
    }
    if let Some(w) = &r.weight_indicator {
        rig.indicator = match w.get_ref().as_str() {
            "dead_line" => crate::rig::Indicator::DeadLine,
            "hook" => crate::rig::Indicator::Hook,
            other => {
                return Err(ctx.err(
                    w.span(),
                    "rig.weight_indicator",
                    format!("unknown weight indicator {other:?}; allowed: dead_line, hook"),
                ))
            }
        };
    }
    rig.tared = r.tared.unwrap_or(false);
    Ok(Some(rig))
}
