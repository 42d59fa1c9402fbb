//! The commands the README and the guide show run as written from the repository's root:
//! every `ssbvb …` line of their `sh` blocks (outputs redirected to a temporary folder),
//! except the viewer (it needs a display; the `view` tests run it under Xvfb) and the
//! benchmark presets (long; the `presets` tests run small ones); and the guide's pipeline
//! file resolves.

use std::path::Path;

use super::{ssbvb, succeeded};

/// The `ssbvb` lines of the ```sh blocks of `markdown`.
fn ssbvb_lines(markdown: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_sh = false;
    for line in markdown.lines() {
        match line.trim() {
            "```sh" => in_sh = true,
            "```" => in_sh = false,
            l if in_sh && l.starts_with("ssbvb ") => out.push(l.to_string()),
            _ => {}
        }
    }
    out
}

#[test]
fn the_readme_and_guide_commands_run_as_written() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = tempfile::tempdir().unwrap();
    let mut ran = 0;
    for doc in ["README.md", "docs/guide.md"] {
        let text = std::fs::read_to_string(root.join(doc)).unwrap();
        let lines = ssbvb_lines(&text);
        assert!(!lines.is_empty(), "{doc} shows no ssbvb command");
        for line in lines {
            let words: Vec<&str> = line.split_whitespace().skip(1).collect();
            if matches!(words.first(), Some(&"view" | &"bench")) {
                continue;
            }
            let mut cmd = ssbvb();
            let mut it = words.iter();
            while let Some(w) = it.next() {
                cmd.arg(w);
                if *w == "-o" {
                    let out = it.next().expect("-o takes a file");
                    cmd.arg(dir.path().join(out));
                }
            }
            let out = cmd.output().unwrap();
            assert!(
                out.status.success(),
                "{doc}: `{line}` failed:\n{}",
                String::from_utf8_lossy(&out.stderr)
            );
            ran += 1;
        }
    }
    assert!(ran >= 8, "{ran} commands ran");
    // The guide's pipeline file from scratch resolves as the guide says.
    let guide = std::fs::read_to_string(root.join("docs/guide.md")).unwrap();
    let ron = guide
        .split("```ron\n")
        .nth(1)
        .and_then(|s| s.split("```").next())
        .expect("the guide shows a pipeline file");
    let file = dir.path().join("my_esvo.ron");
    std::fs::write(&file, ron).unwrap();
    let out = succeeded(ssbvb().args(["pipeline", "check"]).arg(&file));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("esvo_ray_cast"), "{text}");
}

/// `W×H` or `WxH` as `WxH`, or `None` when `text` is not a size.
fn size_of(text: &str) -> Option<String> {
    let text = text.replace('×', "x");
    let (w, h) = text.split_once('x')?;
    let number = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (number(w) && number(h)).then(|| format!("{w}x{h}"))
}

/// The size the README says the first command's `render.png` has ("writes `render.png` at
/// W×H"), held to the `--size` default that `ssbvb render --help` prints. No device needed.
#[test]
fn the_readme_states_the_default_render_size() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let sentence = "writes `render.png` at ";
    let after = readme
        .split_once(sentence)
        .unwrap_or_else(|| panic!("README.md no longer says \"{sentence}W×H\""))
        .1;
    let stated = after.split_whitespace().next().unwrap_or_default();
    let stated = size_of(stated.trim_end_matches([',', '.', ';', ')']))
        .unwrap_or_else(|| panic!("README.md: `{stated}` after \"{sentence}\" is not a size"));

    let out = succeeded(ssbvb().args(["render", "--help"]));
    let help = String::from_utf8_lossy(&out.stdout);
    let option = help
        .split_once("--size")
        .unwrap_or_else(|| panic!("`render --help` names no --size:\n{help}"))
        .1;
    // Only the text of this option: up to the next line that starts an option.
    let option = option.split("\n  -").next().unwrap();
    let default = option
        .split_once("[default: ")
        .and_then(|(_, rest)| rest.split_once(']'))
        .and_then(|(value, _)| size_of(value))
        .unwrap_or_else(|| panic!("`render --help` states no default --size:\n{help}"));

    assert_eq!(
        stated, default,
        "README.md says `render` writes {stated}; `render --help` says --size defaults to {default}"
    );
}
