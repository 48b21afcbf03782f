//! Every loop in a kernel is counted: the proof that lets the kernels compile without wgpu's
//! loop bounding.
//!
//! wgpu (naga 25 on) guards every WGSL loop with a 64-bit iteration counter of its own
//! (`ShaderRuntimeChecks::force_loop_bounding`), so that a loop that never ends cannot
//! hang the GPU. The guard is a second exit the driver's compiler cannot analyse: it no
//! longer knows a `for (var k = 0u; k < 6u; k++)` runs six times, does not unroll it, and a
//! private array indexed by `k` — the assembly's 6 × 6 blocks, the block solve's rows —
//! stays in memory instead of registers. Measured on lavapipe (`holewall bench kernels`,
//! docs/performance.md): the assembly ran in half the time without the guard.
//!
//! The guard may be left out only for shaders without a loop that never ends ("the caller
//! MUST ensure"), which [`check`] proves of a shader's text before
//! [`crate::gpu::GpuContext::pipeline`] compiles it: no `loop` or `while`, and every `for`
//! of the form `for (var k = …; k < B (or ≤ B); k++ | k += L | k = k + L)` with `L` a
//! positive integer literal, neither `k` nor a name in `B` assigned (an element of it
//! included, or its address taken) in the loop's body, `k` not declared again there. WGSL
//! has no recursion, so such a shader ends. (A bound within `L` of the type's largest value
//! could wrap the counter; the kernels' bounds are sizes of buffers, far below it.)

/// A token of WGSL text: an identifier, a number or a punctuation mark, with its line.
#[derive(Clone, Debug, PartialEq)]
struct Token {
    text: String,
    line: usize,
}

/// Operators of two or three characters, longest first.
const OPERATORS: [&str; 20] = [
    "<<=", ">>=", "++", "--", "+=", "-=", "*=", "/=", "%=", "&=", "|=", "^=", "==", "!=", "<=",
    ">=", "&&", "||", "->", "<<",
];

/// Assignment operators: a name before one of these is written.
const ASSIGNMENTS: [&str; 13] = [
    "=", "+=", "-=", "*=", "/=", "%=", "&=", "|=", "^=", "<<=", ">>=", "++", "--",
];

fn tokens(wgsl: &str) -> Vec<Token> {
    let mut out = Vec::new();
    let mut in_block_comment = false;
    for (index, raw) in wgsl.lines().enumerate() {
        let line = index + 1;
        // The composer's directives (#include, #if …) in a shader's source file.
        if raw.trim_start().starts_with('#') {
            continue;
        }
        let chars: Vec<char> = raw.chars().collect();
        let mut i = 0;
        while i < chars.len() {
            if in_block_comment {
                if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    in_block_comment = false;
                    i += 2;
                } else {
                    i += 1;
                }
                continue;
            }
            let c = chars[i];
            if c == '/' && chars.get(i + 1) == Some(&'/') {
                break;
            }
            if c == '/' && chars.get(i + 1) == Some(&'*') {
                in_block_comment = true;
                i += 2;
                continue;
            }
            if c.is_whitespace() {
                i += 1;
                continue;
            }
            let start = i;
            if c.is_alphabetic() || c == '_' {
                while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
            } else if c.is_ascii_digit() {
                // Numbers with their suffixes and exponents: 1u, 0.5lf, 1.0e-9f.
                let hex = chars.get(i + 1).is_some_and(|c| matches!(c, 'x' | 'X'));
                while i < chars.len() {
                    let sign =
                        matches!(chars[i], '-' | '+') && !hex && matches!(chars[i - 1], 'e' | 'E');
                    if !(chars[i].is_alphanumeric() || chars[i] == '.' || sign) {
                        break;
                    }
                    i += 1;
                }
            } else {
                let rest: String = chars[i..chars.len().min(i + 3)].iter().collect();
                let op = OPERATORS.iter().find(|op| rest.starts_with(*op));
                i += op.map_or(1, |op| op.chars().count());
            }
            out.push(Token {
                text: chars[start..i].iter().collect(),
                line,
            });
        }
    }
    out
}

/// Whether `t` is a positive integer literal (`1`, `6u`, `2i`).
fn positive_integer(t: &str) -> bool {
    let digits = t.trim_end_matches(['u', 'i']);
    !digits.is_empty()
        && digits.chars().all(|c| c.is_ascii_digit())
        && digits.parse::<u64>().is_ok_and(|v| v > 0)
}

/// The index of the token that closes the bracket opened at `open`.
fn closing(toks: &[Token], open: usize) -> Option<usize> {
    let (o, c) = match toks[open].text.as_str() {
        "(" => ("(", ")"),
        "{" => ("{", "}"),
        "[" => ("[", "]"),
        _ => return None,
    };
    let mut depth = 0usize;
    for (k, t) in toks.iter().enumerate().skip(open) {
        if t.text == o {
            depth += 1;
        } else if t.text == c {
            depth -= 1;
            if depth == 0 {
                return Some(k);
            }
        }
    }
    None
}

fn is_name(t: &str) -> bool {
    t.chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_')
}

/// Checks that every loop of `wgsl` (a composed kernel, or a shader's source file with its
/// directives) is counted (see the module's documentation); the error names the line and
/// what is wrong.
pub fn check(wgsl: &str) -> Result<(), String> {
    let toks = tokens(wgsl);
    let at = |k: usize| toks.get(k).map_or("", |t| t.text.as_str());
    for (k, t) in toks.iter().enumerate() {
        let line = t.line;
        match t.text.as_str() {
            "loop" | "while" => {
                return Err(format!(
                    "line {line}: `{}`: write a counted `for` (the kernels compile without \
                     wgpu's loop bounding, src/gpu/loops.rs)",
                    t.text
                ))
            }
            "for" => {}
            _ => continue,
        }
        let bad = |why: &str| {
            Err(format!(
                "line {line}: a `for` loop that is not counted: {why} (src/gpu/loops.rs)"
            ))
        };
        if at(k + 1) != "(" || at(k + 2) != "var" || !is_name(at(k + 3)) || at(k + 4) != "=" {
            return bad("its header must start `for (var NAME = …;`");
        }
        let name = at(k + 3).to_string();
        let Some(header_end) = closing(&toks, k + 1) else {
            return bad("its header is not closed");
        };
        let header = &toks[k + 5..header_end];
        let semis: Vec<usize> = header
            .iter()
            .enumerate()
            .filter(|(_, t)| t.text == ";")
            .map(|(j, _)| j)
            .collect();
        if semis.len() != 2 {
            return bad("its header must have an initialiser, a condition and an increment");
        }
        let condition = &header[semis[0] + 1..semis[1]];
        let increment: Vec<&str> = header[semis[1] + 1..]
            .iter()
            .map(|t| t.text.as_str())
            .collect();
        if condition.len() < 3
            || condition[0].text != name
            || !(condition[1].text == "<" || condition[1].text == "<=")
        {
            return bad(&format!(
                "its condition must be `{name} < BOUND` or `{name} <= BOUND`"
            ));
        }
        let bound = &condition[2..];
        let counted = match increment.as_slice() {
            [n, "++"] => *n == name,
            [n, "+=", lit] => *n == name && positive_integer(lit),
            [n, "=", m, "+", lit] => *n == name && *m == name && positive_integer(lit),
            _ => false,
        };
        if !counted {
            return bad(&format!(
                "its increment must be `{name}++`, `{name} += L` or `{name} = {name} + L` with L a \
                 positive integer literal"
            ));
        }
        if at(header_end + 1) != "{" {
            return bad("its body must be a block");
        }
        let Some(body_end) = closing(&toks, header_end + 1) else {
            return bad("its body is not closed");
        };
        let body = &toks[header_end + 2..body_end];
        let mut guarded: Vec<&str> = vec![name.as_str()];
        for (j, b) in bound.iter().enumerate() {
            let field = j > 0 && bound[j - 1].text == ".";
            if is_name(&b.text) && !field {
                guarded.push(b.text.as_str());
            }
        }
        for (j, b) in body.iter().enumerate() {
            if !guarded.contains(&b.text.as_str()) {
                continue;
            }
            let before = if j > 0 { body[j - 1].text.as_str() } else { "" };
            // An element written (`b[i] = …`) counts as the name written.
            let after_at = if body.get(j + 1).is_some_and(|t| t.text == "[") {
                closing(body, j + 1).map_or(j + 1, |close| close + 1)
            } else {
                j + 1
            };
            let after = body.get(after_at).map_or("", |t| t.text.as_str());
            if before == "." {
                continue;
            }
            if ASSIGNMENTS.contains(&after)
                || before == "&"
                || before == "var"
                || before == "let"
                || before == "++"
                || before == "--"
            {
                return Err(format!(
                    "line {}: `{}`, which ends the `for` loop of line {line}, is written, \
                     declared again or its address taken in the loop's body (src/gpu/loops.rs)",
                    b.line, b.text
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::check;

    #[test]
    fn counted_loops_pass() {
        for ok in [
            "fn f() { for (var k = 0u; k < 6u; k = k + 1u) { a[k] = b[k]; } }",
            "fn f() { for (var k = 0u; k < b[0]; k++) { a[k] = b[k]; } }",
            "fn f() { for (var k = r; k < 6u * n; k = k + 6u) { x[k] = 0.0; } }",
            "fn f() { for (var i = dims.begin; i < dims.end; i++) { s.i = 1; } }",
            "fn f() { for (var k = 0u; k <= 13u; k += 2u) { if (k == 3u) { break; } } }",
            "// a loop { while\n/* loop */ fn f() {}",
            "#if LOOP\nfn f() { let e = 1.0e-9f; let w = 2u; }\n#endif",
        ] {
            assert_eq!(check(ok), Ok(()), "{ok}");
        }
    }

    #[test]
    fn loops_that_might_not_end_are_refused() {
        for (bad, says) in [
            ("fn f() {\n loop { if (x) { break; } } }", "line 2: `loop`"),
            ("fn f() { while (x < 1.0) { x = x * 2.0; } }", "`while`"),
            (
                "fn f() { for (var k = 0u; k < n; k = k + s) { } }",
                "increment",
            ),
            (
                "fn f() { for (var k = 0u; k < n; k = k + 0u) { } }",
                "increment",
            ),
            ("fn f() { for (var k = 0u; k < n; k--) { } }", "increment"),
            ("fn f() { for (var k = 10u; k > 0u; k--) { } }", "condition"),
            (
                "fn f() { for (var k = 0u; k < n; k++) {\n k = 0u; } }",
                "line 2: `k`",
            ),
            (
                "fn f() { for (var k = 0u; k < n; k++) { n += 1u; } }",
                "`n`",
            ),
            (
                "fn f() { for (var k = 0u; k < b[0]; k++) { b[0] = 9u; } }",
                "`b`",
            ),
            ("fn f() { for (var k = 0u; k < n; k++) { g(&k); } }", "`k`"),
            (
                "fn f() { for (var k = 0u; k < n; k++) { var k = 0u; } }",
                "`k`",
            ),
            ("fn f() { for (var k = 0u; k < n; k++) { k++; } }", "`k`"),
            ("fn f() { for (; k < n; k++) { } }", "header"),
        ] {
            let err = check(bad).expect_err(bad);
            assert!(err.contains(says), "{bad}: {err}");
        }
    }

    #[test]
    fn every_shader_source_is_counted() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
        let mut seen = 0;
        for sub in [dir.clone(), dir.join("shared")] {
            for entry in std::fs::read_dir(&sub).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == "wgsl") {
                    let text = std::fs::read_to_string(&path).unwrap();
                    if let Err(e) = check(&text) {
                        panic!("{}: {e}", path.display());
                    }
                    seen += 1;
                }
            }
        }
        assert!(seen >= 12, "{seen} shader files");
    }
}
