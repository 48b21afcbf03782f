//! Well path by the minimum-curvature method: position and tangent at any measured depth.
//!
//! Frame: `x` north, `y` east, `z` true vertical depth (down), right-handed; gravity is
//! `+z`. Inclination `I` from vertical, azimuth `A` from north towards east (the drilling
//! convention); the unit tangent is `(sin I cos A, sin I sin A, cos I)`. Between two
//! stations the path is the circular arc (constant dogleg) joining their tangents: the
//! station positions are those of the ratio-factor formula `ΔP = ΔMD/2 (t1 + t2) RF`,
//! `RF = (2/β) tan(β/2)`, and in between the arc itself is evaluated, so positions and
//! tangents are consistent everywhere.

use thiserror::Error;

use crate::physics::vec3::{add, dot, scale, sub, Vec3};

/// One survey station.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurveyStation {
    /// Measured depth (m).
    pub md: f64,
    /// Inclination (degrees, 0 = vertical down, 90 = horizontal), in [0, 180].
    pub inclination_deg: f64,
    /// Azimuth (degrees from north towards east); any finite value, taken modulo 360.
    pub azimuth_deg: f64,
}

/// A survey that cannot describe a well.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SurveyError {
    /// Fewer than two stations.
    #[error("a survey needs at least two stations, got {0}")]
    TooFewStations(usize),
    /// Measured depth not strictly increasing.
    #[error("station {index}: measured depth {md} m is not greater than the previous {previous} m (MD must increase)")]
    MdNotIncreasing {
        /// 0-based station index.
        index: usize,
        /// Its MD.
        md: f64,
        /// The previous MD.
        previous: f64,
    },
    /// Inclination outside [0°, 180°] or a non-finite value.
    #[error("station {index}: inclination {value}° is outside [0°, 180°]")]
    Inclination {
        /// 0-based station index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A non-finite number.
    #[error("station {index}: {what} is not a finite number")]
    NotFinite {
        /// 0-based station index.
        index: usize,
        /// Which field.
        what: &'static str,
    },
}

impl SurveyError {
    /// The 0-based station the error is about, if one.
    pub fn station(&self) -> Option<usize> {
        match self {
            SurveyError::TooFewStations(_) => None,
            SurveyError::MdNotIncreasing { index, .. }
            | SurveyError::Inclination { index, .. }
            | SurveyError::NotFinite { index, .. } => Some(*index),
        }
    }

    /// The message without its `station N:` prefix (for a message that names the line).
    pub fn detail(&self) -> String {
        let s = self.to_string();
        match self.station() {
            Some(_) => s.split_once(": ").map_or(s.clone(), |(_, d)| d.to_string()),
            None => s,
        }
    }
}

/// Unit tangent for inclination and azimuth in radians.
pub fn tangent(inclination: f64, azimuth: f64) -> Vec3<f64> {
    [
        inclination.sin() * azimuth.cos(),
        inclination.sin() * azimuth.sin(),
        inclination.cos(),
    ]
}

/// Dogleg angle between two unit tangents (rad), robust for small angles.
pub fn dogleg(t1: &Vec3<f64>, t2: &Vec3<f64>) -> f64 {
    let d = sub(t2, t1);
    2.0 * (0.5 * dot(&d, &d).sqrt()).min(1.0).asin()
}

/// A well path: stations with their minimum-curvature positions.
#[derive(Clone, Debug)]
pub struct WellPath {
    md: Vec<f64>,
    tangents: Vec<Vec3<f64>>,
    positions: Vec<Vec3<f64>>,
}

impl WellPath {
    /// Builds the path from a survey; the first station sits at `origin` (usually 0).
    pub fn from_survey(
        stations: &[SurveyStation],
        origin: Vec3<f64>,
    ) -> Result<WellPath, SurveyError> {
        if stations.len() < 2 {
            return Err(SurveyError::TooFewStations(stations.len()));
        }
        let mut md = Vec::with_capacity(stations.len());
        let mut tangents = Vec::with_capacity(stations.len());
        for (index, s) in stations.iter().enumerate() {
            for (what, x) in [
                ("md", s.md),
                ("inclination", s.inclination_deg),
                ("azimuth", s.azimuth_deg),
            ] {
                if !x.is_finite() {
                    return Err(SurveyError::NotFinite { index, what });
                }
            }
            if !(0.0..=180.0).contains(&s.inclination_deg) {
                return Err(SurveyError::Inclination {
                    index,
                    value: s.inclination_deg,
                });
            }
            if let Some(&previous) = md.last() {
                if s.md <= previous {
                    return Err(SurveyError::MdNotIncreasing {
                        index,
                        md: s.md,
                        previous,
                    });
                }
            }
            md.push(s.md);
            tangents.push(tangent(
                s.inclination_deg.to_radians(),
                s.azimuth_deg.to_radians(),
            ));
        }
        let mut positions = vec![origin];
        for k in 1..md.len() {
            let p = arc_point(
                &positions[k - 1],
                &tangents[k - 1],
                &tangents[k],
                md[k] - md[k - 1],
                1.0,
            )
            .0;
            positions.push(p);
        }
        Ok(WellPath {
            md,
            tangents,
            positions,
        })
    }

    /// A vertical well from 0 to `depth` m.
    pub fn vertical(depth: f64) -> WellPath {
        let stations = [
            SurveyStation {
                md: 0.0,
                inclination_deg: 0.0,
                azimuth_deg: 0.0,
            },
            SurveyStation {
                md: depth,
                inclination_deg: 0.0,
                azimuth_deg: 0.0,
            },
        ];
        WellPath::from_survey(&stations, [0.0; 3]).expect("a vertical survey is valid")
    }

    /// Build-and-hold: vertical to `kickoff_md`, build at `build_rate_deg_per_30m` to
    /// `hold_inclination_deg` along `azimuth_deg`, then hold to `total_md`.
    pub fn build_and_hold(
        kickoff_md: f64,
        build_rate_deg_per_30m: f64,
        hold_inclination_deg: f64,
        azimuth_deg: f64,
        total_md: f64,
    ) -> Result<WellPath, SurveyError> {
        let build_length = hold_inclination_deg / build_rate_deg_per_30m * 30.0;
        let end_of_build = kickoff_md + build_length;
        let mut stations = vec![
            SurveyStation {
                md: 0.0,
                inclination_deg: 0.0,
                azimuth_deg,
            },
            SurveyStation {
                md: kickoff_md,
                inclination_deg: 0.0,
                azimuth_deg,
            },
        ];
        if end_of_build < total_md {
            stations.push(SurveyStation {
                md: end_of_build,
                inclination_deg: hold_inclination_deg,
                azimuth_deg,
            });
            stations.push(SurveyStation {
                md: total_md,
                inclination_deg: hold_inclination_deg,
                azimuth_deg,
            });
        } else {
            let inc = (total_md - kickoff_md) / 30.0 * build_rate_deg_per_30m;
            stations.push(SurveyStation {
                md: total_md,
                inclination_deg: inc,
                azimuth_deg,
            });
        }
        stations.retain(|s| s.md >= 0.0);
        stations.dedup_by(|b, a| b.md <= a.md);
        WellPath::from_survey(&stations, [0.0; 3])
    }

    /// Measured depth of the first and last station.
    pub fn md_range(&self) -> (f64, f64) {
        (self.md[0], self.md[self.md.len() - 1])
    }

    /// Station measured depths.
    pub fn station_md(&self) -> &[f64] {
        &self.md
    }

    /// Position and unit tangent at measured depth `md` (clamped to the survey's range;
    /// beyond the last station the last tangent is held).
    pub fn at(&self, md: f64) -> (Vec3<f64>, Vec3<f64>) {
        let last = self.md.len() - 1;
        if md >= self.md[last] {
            let p = add(
                &self.positions[last],
                &scale(&self.tangents[last], md - self.md[last]),
            );
            return (p, self.tangents[last]);
        }
        if md <= self.md[0] {
            return (
                add(
                    &self.positions[0],
                    &scale(&self.tangents[0], md - self.md[0]),
                ),
                self.tangents[0],
            );
        }
        let k = self.md.partition_point(|m| *m <= md).clamp(1, last);
        let length = self.md[k] - self.md[k - 1];
        let f = (md - self.md[k - 1]) / length;
        arc_point(
            &self.positions[k - 1],
            &self.tangents[k - 1],
            &self.tangents[k],
            length,
            f,
        )
    }

    /// Dogleg severity of the segment containing `md` (rad/m).
    pub fn curvature(&self, md: f64) -> f64 {
        let last = self.md.len() - 1;
        let k = self.md.partition_point(|m| *m <= md).clamp(1, last);
        dogleg(&self.tangents[k - 1], &self.tangents[k]) / (self.md[k] - self.md[k - 1])
    }
}

/// Point and tangent at fraction `f` of the circular arc of length `length` leaving `p1`
/// with tangent `t1` and arriving with `t2`: `t(f)` is the spherical interpolation of the
/// tangents, `p(f) = p1 + L/(β sin β)·[(cos((1−f)β) − cos β) t1 + (1 − cos fβ) t2]`; at
/// `f = 1` this is the ratio-factor formula.
fn arc_point(
    p1: &Vec3<f64>,
    t1: &Vec3<f64>,
    t2: &Vec3<f64>,
    length: f64,
    f: f64,
) -> (Vec3<f64>, Vec3<f64>) {
    let beta = dogleg(t1, t2);
    if beta < 1e-7 {
        // Straight to O(β²): p = p1 + L[(f − f²/2) t1 + f²/2 t2].
        let p = add(
            p1,
            &add(
                &scale(t1, length * (f - 0.5 * f * f)),
                &scale(t2, length * 0.5 * f * f),
            ),
        );
        let t = add(&scale(t1, 1.0 - f), &scale(t2, f));
        let len = dot(&t, &t).sqrt();
        return (p, scale(&t, 1.0 / len));
    }
    let sb = beta.sin();
    let c = length / (beta * sb);
    let p = add(
        p1,
        &add(
            &scale(t1, c * (((1.0 - f) * beta).cos() - beta.cos())),
            &scale(t2, c * (1.0 - (f * beta).cos())),
        ),
    );
    let t = add(
        &scale(t1, ((1.0 - f) * beta).sin() / sb),
        &scale(t2, (f * beta).sin() / sb),
    );
    (p, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn st(md: f64, inc: f64, azi: f64) -> SurveyStation {
        SurveyStation {
            md,
            inclination_deg: inc,
            azimuth_deg: azi,
        }
    }

    fn close(a: &Vec3<f64>, b: &Vec3<f64>, tol: f64) -> bool {
        (0..3).all(|k| (a[k] - b[k]).abs() <= tol)
    }

    #[test]
    fn hand_computed_survey() {
        // Two stations: MD 1000 → 1100, I 10° → 20°, A 30° → 40°. By hand:
        // cos β = cos(I2 − I1) − sin I1 sin I2 (1 − cos ΔA)
        //       = 0.984808 − 0.173648·0.342020·0.015192 = 0.983905
        // β = 0.179655 rad; RF = 2/β tan(β/2) = 1.002698.
        // ΔN = 50 (sin10 cos30 + sin20 cos40)·RF = 50(0.150384 + 0.262003)·RF = 20.6750
        // ΔE = 50 (sin10 sin30 + sin20 sin40)·RF = 50(0.086824 + 0.219846)·RF = 15.3749
        // ΔV = 50 (cos10 + cos20)·RF = 50(0.984808 + 0.939693)·RF = 96.4847
        let path =
            WellPath::from_survey(&[st(1000.0, 10.0, 30.0), st(1100.0, 20.0, 40.0)], [0.0; 3])
                .unwrap();
        let (p, t) = path.at(1100.0);
        assert!(close(&p, &[20.6750, 15.3749, 96.4847], 1e-4), "{p:?}");
        assert!(close(
            &t,
            &tangent(20f64.to_radians(), 40f64.to_radians()),
            1e-12
        ));
        let beta = dogleg(&tangent(10f64.to_radians(), 30f64.to_radians()), &t);
        assert!((beta - 0.179655).abs() < 1e-6);
    }

    #[test]
    fn azimuth_wraps_through_north() {
        // 350° → 10° is a 20° turn through north, not a 340° one.
        let a = WellPath::from_survey(&[st(0.0, 30.0, 350.0), st(100.0, 30.0, 10.0)], [0.0; 3])
            .unwrap();
        let b = WellPath::from_survey(&[st(0.0, 30.0, -10.0), st(100.0, 30.0, 370.0)], [0.0; 3])
            .unwrap();
        let (pa, _) = a.at(100.0);
        let (pb, _) = b.at(100.0);
        assert!(close(&pa, &pb, 1e-9));
        // Symmetric about north: no net east displacement, north displacement positive.
        assert!(pa[1].abs() < 1e-9 && pa[0] > 0.0, "{pa:?}");
        // Curvature is that of a 20° azimuth turn at 30° inclination.
        let beta = dogleg(
            &tangent(30f64.to_radians(), (-10f64).to_radians()),
            &tangent(30f64.to_radians(), 10f64.to_radians()),
        );
        assert!((a.curvature(50.0) - beta / 100.0).abs() < 1e-12);
        assert!(beta.to_degrees() < 11.0);
    }

    #[test]
    fn arc_is_a_circle_and_consistent() {
        // Quarter circle from vertical to horizontal over πR/2: end at (R, 0, R).
        let r = 500.0;
        let l = std::f64::consts::FRAC_PI_2 * r;
        let path = WellPath::from_survey(&[st(0.0, 0.0, 0.0), st(l, 90.0, 0.0)], [0.0; 3]).unwrap();
        let (p, _) = path.at(l);
        assert!(close(&p, &[r, 0.0, r], 1e-9), "{p:?}");
        for k in 0..=20 {
            let s = l * k as f64 / 20.0;
            let (p, t) = path.at(s);
            // On the circle centred at (R, 0, 0).
            let rr = ((p[0] - r).powi(2) + p[2].powi(2)).sqrt();
            assert!((rr - r).abs() < 1e-9);
            // Tangent is the derivative of position.
            let h = 1e-4;
            let dp = scale(&sub(&path.at(s + h).0, &path.at(s - h).0), 0.5 / h);
            if k > 0 && k < 20 {
                assert!(close(&dp, &t, 1e-7));
            }
        }
    }

    #[test]
    fn straight_and_vertical() {
        let path = WellPath::vertical(1000.0);
        let (p, t) = path.at(400.0);
        assert!(close(&p, &[0.0, 0.0, 400.0], 1e-12) && close(&t, &[0.0, 0.0, 1.0], 1e-15));
        let path =
            WellPath::from_survey(&[st(0.0, 45.0, 90.0), st(100.0, 45.0, 90.0)], [0.0; 3]).unwrap();
        let (p, _) = path.at(100.0);
        let s = 100.0 / 2f64.sqrt();
        assert!(close(&p, &[0.0, s, s], 1e-9), "{p:?}");
    }

    #[test]
    fn build_and_hold_geometry() {
        // Kick off at 500 m, build 3°/30 m to 30° (300 m of build), hold to 2000 m.
        let path = WellPath::build_and_hold(500.0, 3.0, 30.0, 45.0, 2000.0).unwrap();
        let r = 300.0 / 30f64.to_radians();
        let (p, t) = path.at(800.0);
        let horizontal = r * (1.0 - 30f64.to_radians().cos());
        let tvd = 500.0 + r * 30f64.to_radians().sin();
        assert!((p[2] - tvd).abs() < 1e-9 && ((p[0].hypot(p[1])) - horizontal).abs() < 1e-9);
        assert!(close(
            &t,
            &tangent(30f64.to_radians(), 45f64.to_radians()),
            1e-12
        ));
        let (p_end, _) = path.at(2000.0);
        assert!((p_end[2] - (tvd + 1200.0 * 30f64.to_radians().cos())).abs() < 1e-9);
    }

    #[test]
    fn bad_surveys_are_rejected() {
        assert_eq!(
            WellPath::from_survey(&[st(0.0, 0.0, 0.0)], [0.0; 3]).unwrap_err(),
            SurveyError::TooFewStations(1)
        );
        assert!(matches!(
            WellPath::from_survey(&[st(0.0, 0.0, 0.0), st(0.0, 1.0, 0.0)], [0.0; 3]),
            Err(SurveyError::MdNotIncreasing { index: 1, .. })
        ));
        assert!(matches!(
            WellPath::from_survey(&[st(0.0, 0.0, 0.0), st(10.0, 181.0, 0.0)], [0.0; 3]),
            Err(SurveyError::Inclination { index: 1, .. })
        ));
        assert!(matches!(
            WellPath::from_survey(&[st(0.0, -1.0, 0.0), st(10.0, 1.0, 0.0)], [0.0; 3]),
            Err(SurveyError::Inclination { index: 0, .. })
        ));
        assert!(matches!(
            WellPath::from_survey(&[st(0.0, 0.0, 0.0), st(10.0, f64::NAN, 0.0)], [0.0; 3]),
            Err(SurveyError::NotFinite { index: 1, .. })
        ));
    }
}
