//! Ensembles: one case, many parameter variants (issue 5). A variant is a list of
//! overrides of the case — contact-law parameters (all sites, or one stabilizer's), the
//! stabilizer layout (blade diameter, distance from the bit), RPM, WOB and TOB — given as
//! a CSV (one row per variant, one column per key) or as a grid in the case's
//! `[ensemble]` table (every combination).
//!
//! Keys (values in SI, or `"<number> <unit>"`):
//!
//! | key | meaning | unit | allowed |
//! |---|---|---|---|
//! | `mu`, `mu_t`, `mu_l` (`.stabK`) | friction (both, circumferential, axial) | – | 0 … 2 |
//! | `k_e` (`.stabK`) | wall stiffness | N/m^m | 0 < … ≤ 1e12 |
//! | `c` (`.stabK`) | wall damping | N·s/m | ≥ 0 |
//! | `m` (`.stabK`) | spring exponent | – | 0 < … ≤ 3 |
//! | `eps` (`.stabK`) | friction regularisation speed | m/s | 0 < … ≤ 10 |
//! | `rpm` | rotary speed | rad/s | 0 … 1000 rpm |
//! | `wob`, `tob` | weight and torque on bit | N, N·m | 0 … 1e7 N, 0 … 1e6 N·m |
//! | `stabK.blade` | blade diameter of stabilizer K | m | ≤ hole diameter |
//! | `stabK.from_bit` | distance of stabilizer K's site from the bit | m | 0 < … < bit MD |
//! | `depth` | bit depth (MD): the case rebuilt with `well.total_md` there (the string cut at the surface, the hole sections kept) | m | 0 < … ≤ 20 km, within the hole |
//! | `mode` | operation: `rotating`, `tripping_in`, `tripping_out`, `sliding`, `reaming`, `back_reaming` (the case rebuilt with it; a distribution draws their codes 0 … 5) | – | one of those |
//! | `ecc` | centre-of-mass offset of every BHA component (dynamics: a mass imbalance; replaces the case's) | m | 0 … 50 mm |
//! | `bend` | angle of every bent sub / bent housing of the case (`[[string]].bend`) | degrees unless a unit is given | 0 … 5° |
//! | `layout` | one of the case's `ensemble.layouts` (1, 2, …): its `stabK.from_bit` / `stabK.blade` values together | – | 1 … number of layouts |
//!
//! The case file's own keys for the same inputs (`operation.weight_on_bit`, `contact.eps`,
//! `hole.friction`, …) take the same ranges ([`crate::keys::Param::range`]).
//!
//! Stabilizers are numbered from the bit up (`stab1` nearest the bit); a key without
//! `.stabK` applies to every contact site.

pub mod job;
pub mod measured;
pub mod plots;
pub mod qoi;
pub mod report;
pub mod runner;
pub mod store;
pub mod tendency_map;
mod variant;

pub use crate::keys::{Key, KeyError, Mode, Param, Value, KEY_FORMS};
pub(crate) use variant::input_csv;
pub use variant::{
    apply, apply_with_sites, case_variants, placed_case, sample_variants, variant_case,
    variants_from_csv, variants_from_csv_text, variants_from_grid, Variant, VariantError,
};
