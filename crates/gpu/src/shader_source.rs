//! WGSL includes: a line `//#include "name.inc.wgsl"` is replaced by that file's text.
//!
//! WGSL has no include mechanism; this is the smallest one that keeps error positions
//! honest: [`Preprocessed::locate`] maps a line of the combined source back to the file
//! and line it came from, so tools report `common.inc.wgsl:12` and not a line of a
//! generated text. Include-only files end in `.inc.wgsl` and are not validated alone.

/// The directive prefix.
pub const INCLUDE: &str = "//#include";

/// A combined source with a map back to the original files.
#[derive(Debug, Clone, PartialEq)]
pub struct Preprocessed {
    /// The combined WGSL.
    pub source: String,
    /// `(first line in source (1-based), file, first line in file (1-based))` per chunk.
    pub map: Vec<(usize, String, usize)>,
}

impl Preprocessed {
    /// The file and line that line `line` (1-based) of [`Preprocessed::source`] came from.
    pub fn locate(&self, line: usize) -> (&str, usize) {
        let i = self
            .map
            .partition_point(|(start, _, _)| *start <= line)
            .saturating_sub(1);
        match self.map.get(i) {
            Some((start, file, first)) => (file.as_str(), first + (line - start)),
            None => ("?", line),
        }
    }
}

/// Expands includes in `main` (named `main_name`), reading included files with `read`.
/// Includes nest; an include cycle or a missing file is an error naming the file and line.
pub fn preprocess(
    main_name: &str,
    main: &str,
    read: &dyn Fn(&str) -> Option<String>,
) -> Result<Preprocessed, String> {
    let mut out = Preprocessed {
        source: String::new(),
        map: Vec::new(),
    };
    let mut line_no = 1usize;
    expand(
        main_name,
        main,
        read,
        &mut out,
        &mut line_no,
        &mut Vec::new(),
    )?;
    Ok(out)
}

fn expand(
    name: &str,
    text: &str,
    read: &dyn Fn(&str) -> Option<String>,
    out: &mut Preprocessed,
    out_line: &mut usize,
    stack: &mut Vec<String>,
) -> Result<(), String> {
    if stack.iter().any(|s| s == name) {
        return Err(format!("include cycle: {} -> {name}", stack.join(" -> ")));
    }
    stack.push(name.to_string());
    let mut chunk_open = false;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(rest) = trimmed.strip_prefix(INCLUDE) {
            let target = rest.trim().trim_matches('"');
            let body = read(target)
                .ok_or_else(|| format!("{name}:{}: cannot include `{target}`", i + 1))?;
            expand(target, &body, read, out, out_line, stack)?;
            chunk_open = false;
            continue;
        }
        if !chunk_open {
            out.map.push((*out_line, name.to_string(), i + 1));
            chunk_open = true;
        }
        out.source.push_str(line);
        out.source.push('\n');
        *out_line += 1;
    }
    stack.pop();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn includes_expand_and_lines_map_back() {
        let read = |n: &str| match n {
            "a.inc.wgsl" => Some("const A: u32 = 1u;\nconst B: u32 = 2u;".to_string()),
            "loop.inc.wgsl" => Some("//#include \"loop.inc.wgsl\"".to_string()),
            _ => None,
        };
        let p = preprocess(
            "main.wgsl",
            "// top\n//#include \"a.inc.wgsl\"\nfn f() {}\n",
            &read,
        )
        .unwrap();
        assert_eq!(
            p.source,
            "// top\nconst A: u32 = 1u;\nconst B: u32 = 2u;\nfn f() {}\n"
        );
        assert_eq!(p.locate(1), ("main.wgsl", 1));
        assert_eq!(p.locate(3), ("a.inc.wgsl", 2));
        assert_eq!(p.locate(4), ("main.wgsl", 3));
        assert!(
            preprocess("m", "//#include \"nope.wgsl\"", &read)
                .unwrap_err()
                .contains("m:1: cannot include")
        );
        assert!(
            preprocess("m", "//#include \"loop.inc.wgsl\"", &read)
                .unwrap_err()
                .contains("cycle")
        );
    }
}
