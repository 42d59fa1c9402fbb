//! The Markdown report of `mutate-shaders`: per file the counts, then every missed and
//! timed-out mutant with its line, for a survivor to be explained or killed by a new test.

use std::path::Path;
use std::time::Duration;

use anyhow::{Context, Result};

use super::sites::{Kind, Mutant};

/// What happened to one mutant.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    /// A test failed; the first failing test's name (empty when the log named none).
    Caught(String),
    /// Every test passed.
    Missed,
    /// The run took longer than the limit (a hang, or a far slower shader).
    Timeout,
    /// naga rejected the mutant (or a pass's layout check did).
    Invalid,
}

/// The mutants of one file and their outcomes.
#[derive(Debug)]
pub struct FileResult {
    /// File name under `shaders/`.
    pub file: String,
    /// The test filters used.
    pub filters: Vec<String>,
    /// Wall time of the unmutated run.
    pub baseline: Duration,
    /// Every mutant run, in file order.
    pub outcomes: Vec<(Mutant, Outcome)>,
}

/// Counts of one file (or all): mutants, caught, missed, timeouts, invalid.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Counts {
    /// All mutants.
    pub mutants: usize,
    /// Caught by a failing test.
    pub caught: usize,
    /// Not noticed.
    pub missed: usize,
    /// Timed out.
    pub timeouts: usize,
    /// Rejected by naga.
    pub invalid: usize,
}

impl Counts {
    fn add(&mut self, o: &Outcome) {
        self.mutants += 1;
        match o {
            Outcome::Caught(_) => self.caught += 1,
            Outcome::Missed => self.missed += 1,
            Outcome::Timeout => self.timeouts += 1,
            Outcome::Invalid => self.invalid += 1,
        }
    }

    /// Caught over viable (caught + missed + timeouts), in percent.
    pub fn caught_percent(&self) -> f64 {
        let viable = self.caught + self.missed + self.timeouts;
        if viable == 0 {
            100.0
        } else {
            100.0 * self.caught as f64 / viable as f64
        }
    }
}

impl FileResult {
    /// This file's counts (all kinds, or one).
    pub fn counts(&self, kind: Option<Kind>) -> Counts {
        let mut c = Counts::default();
        for (m, o) in &self.outcomes {
            if kind.is_none_or(|k| k == m.kind) {
                c.add(o);
            }
        }
        c
    }
}

fn row(name: &str, c: &Counts) -> String {
    format!(
        "| {name} | {} | {} | {} | {} | {} | {:.1} % |\n",
        c.mutants,
        c.caught,
        c.missed,
        c.timeouts,
        c.invalid,
        c.caught_percent()
    )
}

/// The report as Markdown.
pub fn render(results: &[FileResult], args: &[String], elapsed: Duration) -> String {
    let mut s = String::from("# Shader mutation report\n\n");
    s.push_str(&format!(
        "`cargo xtask mutate-shaders {}`, {:.0} s. Caught / viable counts timeouts as not caught.\n\n",
        args.join(" "),
        elapsed.as_secs_f64()
    ));
    s.push_str("| file | mutants | caught | missed | timeouts | invalid | caught / viable |\n");
    s.push_str("|---|---:|---:|---:|---:|---:|---:|\n");
    let mut total = Counts::default();
    for r in results {
        for (_, o) in &r.outcomes {
            total.add(o);
        }
        s.push_str(&row(&format!("`{}`", r.file), &r.counts(None)));
    }
    s.push_str(&row("**total**", &total));
    let kinds = [
        Kind::Operator,
        Kind::Constant,
        Kind::SelectArms,
        Kind::NegatedCondition,
        Kind::DeletedStatement,
    ];
    for r in results {
        s.push_str(&format!(
            "\n## `{}`\n\nTests: {} (unmutated run {:.1} s).\n\n| kind | mutants | caught | missed | timeouts | invalid | caught / viable |\n|---|---:|---:|---:|---:|---:|---:|\n",
            r.file,
            if r.filters.is_empty() {
                "all GPU tests".to_string()
            } else {
                r.filters.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(", ")
            },
            r.baseline.as_secs_f64()
        ));
        for k in kinds {
            let c = r.counts(Some(k));
            if c.mutants > 0 {
                s.push_str(&row(k.name(), &c));
            }
        }
        for (title, want) in [("Missed", Outcome::Missed), ("Timed out", Outcome::Timeout)] {
            let list: Vec<_> = r.outcomes.iter().filter(|(_, o)| *o == want).collect();
            if !list.is_empty() {
                s.push_str(&format!("\n{title}:\n\n"));
                for (m, _) in list {
                    s.push_str(&format!("- {}\n", m.describe()));
                }
            }
        }
    }
    s
}

/// Writes the report (temporary file, then rename).
pub fn write(
    path: &Path,
    results: &[FileResult],
    args: &[String],
    elapsed: Duration,
) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let tmp = path.with_extension("md.tmp");
    std::fs::write(&tmp, render(results, args, elapsed))
        .with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("renaming to {}", path.display()))
}

/// One line per file on stderr.
pub fn print_summary(results: &[FileResult]) {
    for r in results {
        let c = r.counts(None);
        eprintln!(
            "mutate-shaders: {}: {} mutants, {} caught, {} missed, {} timeouts, {} invalid ({:.1} % caught)",
            r.file,
            c.mutants,
            c.caught,
            c.missed,
            c.timeouts,
            c.invalid,
            c.caught_percent()
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_report_list_the_survivors() {
        let src = "fn f() { x = a < b; y += 1u; }\n";
        let ms = super::super::sites::mutants(src);
        assert!(ms.len() >= 3);
        let outcomes = vec![
            (ms[0].clone(), Outcome::Caught("t::a".into())),
            (ms[1].clone(), Outcome::Missed),
            (ms[2].clone(), Outcome::Invalid),
        ];
        let r = FileResult {
            file: "f.wgsl".into(),
            filters: vec!["t::".into()],
            baseline: Duration::from_secs(2),
            outcomes,
        };
        let c = r.counts(None);
        assert_eq!((c.mutants, c.caught, c.missed, c.invalid), (3, 1, 1, 1));
        assert_eq!(c.caught_percent(), 50.0);
        let md = render(&[r], &["f.wgsl".into()], Duration::from_secs(5));
        assert!(
            md.contains("| `f.wgsl` | 3 | 1 | 1 | 0 | 1 | 50.0 % |"),
            "{md}"
        );
        assert!(md.contains(&format!("- {}", ms[1].describe())), "{md}");
        assert!(!md.contains(&format!("- {}", ms[0].describe())), "{md}");
    }
}
