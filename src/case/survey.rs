//! `[well]`: the well path; a survey CSV read, checked and judged for plausibility.

use super::*;

pub(super) fn read_survey(
    path: &Path,
    ctx: &Ctx,
    span: std::ops::Range<usize>,
) -> Result<Vec<(SurveyStation, usize)>, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        ctx.err(
            span.clone(),
            "well.survey",
            format!("{}: {e}", path.display()),
        )
    })?;
    survey_from_text(&path.display().to_string(), &text)
}

/// The stations of a survey CSV (`md, inclination, azimuth`, an optional header naming
/// `ft` for feet) with their 1-based lines; `source` names it in messages.
pub fn survey_from_text(
    source: &str,
    text: &str,
) -> Result<Vec<(SurveyStation, usize)>, InputError> {
    let mut out = Vec::new();
    let mut md_factor = 1.0;
    for (k, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if line.trim().is_empty() {
            continue;
        }
        let bad = |msg: String| InputError {
            source_name: source.to_string(),
            line: k + 1,
            key: "survey".into(),
            message: msg,
        };
        if fields.len() != 3 {
            return Err(bad(format!(
                "expected 3 columns (md, inclination, azimuth), got {}",
                fields.len()
            )));
        }
        if fields[0].parse::<f64>().is_err() {
            if k == 0 {
                if fields[0].to_ascii_lowercase().contains("ft") {
                    md_factor = 0.3048;
                }
                continue;
            }
            return Err(bad(format!("md {:?} is not a number", fields[0])));
        }
        let parse = |s: &str, what: &str| {
            s.parse::<f64>()
                .map_err(|_| bad(format!("{what} {s:?} is not a number")))
        };
        out.push((
            SurveyStation {
                md: parse(fields[0], "md")? * md_factor,
                inclination_deg: parse(fields[1], "inclination")?,
                azimuth_deg: {
                    let a = parse(fields[2], "azimuth")?;
                    if !(0.0..=360.0).contains(&a) {
                        return Err(bad(format!(
                            "azimuth {}° is outside 0 … 360° (did you mean {}°?)",
                            crate::units::show(a),
                            crate::units::show(a.rem_euclid(360.0))
                        )));
                    }
                    a
                },
            },
            k + 1,
        ));
    }
    Ok(out)
}

/// `[well]`: the well path (vertical, build and hold, or a survey read and checked), and
/// the survey's stations with their lines (for [`survey_plausibility`]).
#[allow(clippy::type_complexity)]
pub(super) fn read_well(
    ctx: &Ctx,
    spec: &CaseSpec,
    path: &Path,
    bit_md: f64,
    read_before: Option<(PathBuf, Vec<(SurveyStation, usize)>)>,
) -> Result<(WellPath, Option<(PathBuf, Vec<(SurveyStation, usize)>)>), InputError> {
    let mut survey_read: Option<(PathBuf, Vec<(SurveyStation, usize)>)> = None;
    let well = match spec.well.profile.get_ref().as_str() {
        "vertical" => WellPath::vertical(bit_md),
        "build_and_hold" => {
            let need = |q: &Option<Q>, key: &str| {
                q.clone().ok_or_else(|| {
                    ctx.err(
                        spec.well.profile.span(),
                        key,
                        "required by profile = \"build_and_hold\"",
                    )
                })
            };
            let kop = ctx.quantity(
                &need(&spec.well.kickoff_md, "well.kickoff_md")?,
                "well.kickoff_md",
                Dimension::Length,
                |x| (0.0..bit_md).contains(&x),
                "0 ≤ kickoff_md < total_md",
            )?;
            let rate = spec.well.build_rate_deg_per_30m.as_ref().ok_or_else(|| {
                ctx.err(
                    spec.well.profile.span(),
                    "well.build_rate_deg_per_30m",
                    "required by profile = \"build_and_hold\"",
                )
            })?;
            let rate = ctx.number(
                rate,
                "well.build_rate_deg_per_30m",
                |x| x > 0.0 && x <= 30.0,
                "0 < rate ≤ 30 °/30 m",
            )?;
            let inc = ctx.angle(
                &need(&spec.well.hold_inclination, "well.hold_inclination")?,
                "well.hold_inclination",
                |x| (0.0..=180.0).contains(&x),
                "0° … 180°",
            )?;
            let azi = ctx.angle(
                &need(&spec.well.azimuth, "well.azimuth")?,
                "well.azimuth",
                |x| (0.0..=360.0).contains(&x),
                "0° … 360°",
            )?;
            WellPath::build_and_hold(kop, rate, inc, azi, bit_md)
                .map_err(|e| ctx.err(spec.well.profile.span(), "well", e.to_string()))?
        }
        "survey" => {
            let file = spec.well.survey.as_ref().ok_or_else(|| {
                ctx.err(
                    spec.well.profile.span(),
                    "well.survey",
                    "required by profile = \"survey\"",
                )
            })?;
            let survey_path = path.parent().unwrap_or(Path::new(".")).join(file.get_ref());
            let read = match read_before {
                Some((before, read)) if before == survey_path => read,
                _ => read_survey(&survey_path, ctx, file.span())?,
            };
            let survey_err = |line: usize, message: String| InputError {
                source_name: survey_path.display().to_string(),
                line,
                key: "survey".into(),
                message,
            };
            let stations: Vec<SurveyStation> = read.iter().map(|(s, _)| *s).collect();
            let well_path =
                WellPath::from_survey(&stations, [0.0; 3]).map_err(|e| match e.station() {
                    Some(i) => survey_err(read[i].1, e.detail()),
                    None => survey_err(0, e.to_string()),
                })?;
            // The survey must cover the hole: from the surface (MD 0) to the string's depth.
            if let Some((first, line)) = read.first() {
                if first.md != 0.0 {
                    return Err(survey_err(
                        *line,
                        format!(
                            "the first station is at MD {} m; a survey starts at the surface \
                             (MD 0 m): add a station \"0, 0, 0\" (or the tie-in) above it",
                            crate::units::show(first.md)
                        ),
                    ));
                }
            }
            if let Some((last, line)) = read.last() {
                // A survey ends above the bit (the MWD sensor rides 10–25 m above it): up to
                // SURVEY_PROJECTION_M it is projected to the bit along its last tangent
                // (`WellPath` holds the last station's inclination and azimuth past it;
                // `survey_projection_warning` says so); farther, refused.
                let short = bit_md - last.md;
                if read.len() >= 2 && short > crate::units::SURVEY_PROJECTION_M {
                    return Err(survey_err(
                        *line,
                        format!(
                            "the last station is at MD {} m, {} m above the bit at {} m \
                             (well.total_md); a survey is projected to the bit along its \
                             last tangent for at most {} m (the sensor's offset): add \
                             stations down to the bit",
                            crate::units::show(last.md),
                            crate::units::show(short),
                            crate::units::show(bit_md),
                            crate::units::show(crate::units::SURVEY_PROJECTION_M),
                        ),
                    ));
                }
            }
            survey_read = Some((survey_path, read));
            well_path
        }
        other => {
            return Err(ctx.err(
                spec.well.profile.span(),
                "well.profile",
                format!("unknown profile {other:?}; allowed: vertical, build_and_hold, survey"),
            ))
        }
    };
    Ok((well, survey_read))
}

/// The warning for a survey `read` from `source` that ends above the bit at `bit_md` (m)
/// by more than 0.1 m (less is a unit's rounding), projected to it along its last tangent;
/// `None` otherwise.
pub fn survey_projection_warning(
    source: &str,
    read: &[(SurveyStation, usize)],
    bit_md: f64,
) -> Option<String> {
    let (last, line) = read.last()?;
    let short = bit_md - last.md;
    (read.len() >= 2 && short > 0.1).then(|| {
        format!(
            "{source}:{line}: the survey ends at MD {} m, {} m above the bit: projected to \
             the bit along its last station's inclination and azimuth ({}°, {}°)",
            crate::units::show(last.md),
            crate::units::show(short),
            crate::units::show(last.inclination_deg),
            crate::units::show(last.azimuth_deg),
        )
    })
}

/// The plausibility of a survey's stations (issue 23), one policy with
/// [`crate::units::bare_number_trap`]'s: an error where a unit mix-up or a typo is far
/// likelier than the well, a warning where the well is merely unusual.
/// - the last station past `SURVEY_PAST_CASE_FACTOR` × the deepest MD the case uses
///   (`deepest`: the bit, the hole sections): MD in feet read as metres, most likely;
/// - a dogleg severity between two stations above `limit` °/30 m: refused (a typo in a
///   station); above [`crate::units::DOGLEG_WARNING_DEG_PER_30M`]: a warning.
pub fn survey_plausibility(
    source: &str,
    read: &[(SurveyStation, usize)],
    deepest: f64,
    limit: f64,
) -> Result<Vec<String>, InputError> {
    use crate::units::show;
    let err = |line: usize, message: String| InputError {
        source_name: source.to_string(),
        line,
        key: "survey".into(),
        message,
    };
    let mut warnings = Vec::new();
    if let Some((last, line)) = read.last() {
        let ratio = last.md / deepest;
        if ratio > crate::units::SURVEY_PAST_CASE_FACTOR {
            let feet = if (3.0..=3.6).contains(&ratio) {
                " — that is the ratio of a foot to a metre: is the survey's MD in feet? \
                 Name the unit in the header (`md_ft, inclination_deg, azimuth_deg`)"
                    .to_string()
            } else {
                String::new()
            };
            return Err(err(
                *line,
                format!(
                    "the survey runs to MD {} m, {:.2}× the deepest MD of the case ({} m: \
                     well.total_md and the [[hole]] sections){feet}; a survey longer than \
                     the hole on purpose: end it within {}× of it",
                    show(last.md),
                    ratio,
                    show(deepest),
                    crate::units::SURVEY_PAST_CASE_FACTOR
                ),
            ));
        }
    }
    for w in read.windows(2) {
        let ((a, _), (b, line)) = (&w[0], &w[1]);
        let (i1, i2) = (
            a.inclination_deg.to_radians(),
            b.inclination_deg.to_radians(),
        );
        let da = (b.azimuth_deg - a.azimuth_deg).to_radians();
        let cos = (i1.cos() * i2.cos() + i1.sin() * i2.sin() * da.cos()).clamp(-1.0, 1.0);
        let dogleg = cos.acos().to_degrees();
        let dls = dogleg / (b.md - a.md) * 30.0;
        let what = format!(
            "a dogleg of {:.1}° over {} m (MD {} → {} m, inclination {} → {}°, azimuth {} → \
             {}°) is {:.1}°/30 m",
            dogleg,
            show(b.md - a.md),
            show(a.md),
            show(b.md),
            show(a.inclination_deg),
            show(b.inclination_deg),
            show(a.azimuth_deg),
            show(b.azimuth_deg),
            dls
        );
        if dls > limit {
            return Err(err(
                *line,
                format!(
                    "{what}, above the limit of {}°/30 m: a typo in a station? (for a \
                     short-radius well, raise well.max_dogleg_deg_per_30m)",
                    show(limit)
                ),
            ));
        }
        if dls > crate::units::DOGLEG_WARNING_DEG_PER_30M {
            warnings.push(format!(
                "{source}:{line}: {what}, sharper than long- and medium-radius builds \
                 ({}°/30 m): check the station",
                show(crate::units::DOGLEG_WARNING_DEG_PER_30M)
            ));
        }
    }
    Ok(warnings)
}
