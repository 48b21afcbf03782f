//! Assembles the WGSL text of a kernel for one feature set.
//!
//! naga does not remove branches made dead by override constants (platform notes), so the
//! kernel sources carry line directives and only the lines a scene needs are kept:
//!
//! - `#if FLAG` / `#if !FLAG` … `#else` … `#endif` (nestable);
//! - `#include "shared/NAME.wgsl"` pastes a file of `shaders/shared/` (processed too).
//!
//! The first line of the result defines the float type: `alias real = f32;` (or `f64`).
//! The text is also the pipeline-cache key ([`crate::gpu::GpuContext::pipeline`]).

use std::collections::BTreeSet;

use crate::error::GpuError;

/// The shader sources, embedded at build time.
pub const SHADERS: &[(&str, &str)] = &[
    ("contact.wgsl", include_str!("../../shaders/contact.wgsl")),
    ("block_lu.wgsl", include_str!("../../shaders/block_lu.wgsl")),
    ("block_cr.wgsl", include_str!("../../shaders/block_cr.wgsl")),
    ("assemble.wgsl", include_str!("../../shaders/assemble.wgsl")),
    ("update.wgsl", include_str!("../../shaders/update.wgsl")),
    ("beam.wgsl", include_str!("../../shaders/beam.wgsl")),
    ("sites.wgsl", include_str!("../../shaders/sites.wgsl")),
    ("dynamics.wgsl", include_str!("../../shaders/dynamics.wgsl")),
    (
        "shared/math_f64.wgsl",
        include_str!("../../shaders/shared/math_f64.wgsl"),
    ),
    (
        "shared/finite.wgsl",
        include_str!("../../shaders/shared/finite.wgsl"),
    ),
    (
        "shared/rotation_exp.wgsl",
        include_str!("../../shaders/shared/rotation_exp.wgsl"),
    ),
    (
        "shared/rotation_log.wgsl",
        include_str!("../../shaders/shared/rotation_log.wgsl"),
    ),
    (
        "shared/chain_solve.wgsl",
        include_str!("../../shaders/shared/chain_solve.wgsl"),
    ),
    (
        "shared/listed.wgsl",
        include_str!("../../shaders/shared/listed.wgsl"),
    ),
    (
        "shared/layout.wgsl",
        include_str!("../../shaders/shared/layout.wgsl"),
    ),
];

/// The source text of a shader by its path under `shaders/`.
pub fn source(name: &str) -> Result<&'static str, GpuError> {
    SHADERS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, s)| *s)
        .ok_or_else(|| GpuError::Shader(format!("no shader named {name}")))
}

/// Composes `name` with each flag of `flags` whose condition holds, and `F64` where `f64`
/// (which also selects the float type).
pub fn compose_if(
    name: &str,
    flags: &[(&'static str, bool)],
    f64: bool,
) -> Result<String, GpuError> {
    let mut set: BTreeSet<&str> = flags.iter().filter(|f| f.1).map(|f| f.0).collect();
    if f64 {
        set.insert("F64");
    }
    compose(name, &set, f64)
}

/// Composes `name` with the `#if` flags in `flags` (the caller adds `F64` for f64; see
/// [`compose_if`], which does).
pub fn compose(name: &str, flags: &BTreeSet<&str>, f64: bool) -> Result<String, GpuError> {
    let mut out = String::new();
    out.push_str(if f64 {
        "alias real = f64;\n"
    } else {
        "alias real = f32;\n"
    });
    expand(name, flags, &mut out, 0)?;
    Ok(out)
}

fn expand(
    name: &str,
    flags: &BTreeSet<&str>,
    out: &mut String,
    depth: usize,
) -> Result<(), GpuError> {
    if depth > 8 {
        return Err(GpuError::Shader(format!(
            "#include nested too deep at {name}"
        )));
    }
    let text = source(name)?;
    // Each entry: (this branch is active, some earlier branch of this #if was active).
    let mut stack: Vec<(bool, bool)> = Vec::new();
    let active = |stack: &Vec<(bool, bool)>| stack.iter().all(|(a, _)| *a);
    for (lineno, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        let here = || format!("{name}:{}", lineno + 1);
        if let Some(cond) = trimmed.strip_prefix("#if ") {
            let cond = cond.trim();
            let value = match cond.strip_prefix('!') {
                Some(flag) => !flags.contains(flag.trim()),
                None => flags.contains(cond),
            };
            stack.push((value, value));
        } else if trimmed.starts_with("#else") {
            let top = stack
                .last_mut()
                .ok_or_else(|| GpuError::Shader(format!("{}: #else without #if", here())))?;
            *top = (!top.1, true);
        } else if trimmed.starts_with("#endif") {
            stack
                .pop()
                .ok_or_else(|| GpuError::Shader(format!("{}: #endif without #if", here())))?;
        } else if let Some(rest) = trimmed.strip_prefix("#include ") {
            if active(&stack) {
                let inc = rest.trim().trim_matches('"');
                expand(inc, flags, out, depth + 1)?;
            }
        } else if active(&stack) {
            out.push_str(line);
            out.push('\n');
        }
    }
    if !stack.is_empty() {
        return Err(GpuError::Shader(format!("{name}: #if without #endif")));
    }
    Ok(())
}

/// Validates WGSL with naga (no GPU needed), with `f64` allowed, and checks that its every
/// loop is counted ([`crate::gpu::loops::check`]).
pub fn validate(wgsl: &str) -> Result<(), GpuError> {
    let module =
        naga::front::wgsl::parse_str(wgsl).map_err(|e| GpuError::Shader(e.emit_to_string(wgsl)))?;
    let mut validator = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::FLOAT64,
    );
    validator
        .validate(&module)
        .map_err(|e| GpuError::Shader(e.emit_to_string(wgsl)))?;
    // What the GPU context requires before it compiles without loop bounding.
    crate::gpu::loops::check(wgsl).map_err(GpuError::Shader)
}
