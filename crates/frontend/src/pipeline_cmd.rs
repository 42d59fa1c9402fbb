//! `ssbvb pipeline check <file.ron>`: resolve a pipeline and print its schedule;
//! `ssbvb pipeline kinds [NAME] [--markdown]`: the pass-kind reference
//! ([`crate::pipeline_kinds`]).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Subcommand;

/// Pipeline subcommands.
#[derive(Subcommand)]
pub enum PipelineCommand {
    /// Resolve a pipeline file: print the schedule (pass order, resources with sizes,
    /// aliasing, pruned items); exit non-zero with every error otherwise.
    Check {
        /// The pipeline file.
        file: PathBuf,
        /// Screen size for the resource sizes in the report.
        #[arg(long, default_value = "1280x720", value_parser = parse_size)]
        size: (u32, u32),
    },
    /// List the pass kinds a pipeline file can use, from the code's own specs: what each
    /// does, its slots and parameters (type, default, allowed values) and the bundled
    /// pipelines that use it.
    Kinds {
        /// One kind to show whole.
        name: Option<String>,
        /// Write the whole reference as Markdown (`docs/pipelines.md`).
        #[arg(long, conflicts_with = "name")]
        markdown: bool,
    },
    /// List the SSBVB forms (the engine's one table): each form's name, pipeline file,
    /// what it is, whether the adapter rule may choose it (and why) and whether the
    /// calibration measures it.
    Forms {
        /// Print the table as JSON (what `cargo xtask gpu-bench` reads).
        #[arg(long)]
        json: bool,
    },
}

pub use ssbvb_engine::values::parse_size;

/// Runs a pipeline subcommand.
pub fn run(cmd: &PipelineCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        PipelineCommand::Kinds { name, markdown } => {
            if *markdown {
                print!("{}", crate::pipeline_kinds::markdown());
            } else {
                print!("{}", crate::pipeline_kinds::text(name.as_deref())?);
            }
            Ok(ExitCode::SUCCESS)
        }
        PipelineCommand::Forms { json } => {
            print!("{}", forms_text(*json)?);
            Ok(ExitCode::SUCCESS)
        }
        PipelineCommand::Check { file, size } => match ssbvb_graph::resolve_file(file) {
            Ok(p) => {
                print!("{}", p.describe(*size));
                Ok(ExitCode::SUCCESS)
            }
            Err(e) => {
                eprint!("{e}");
                Ok(ExitCode::FAILURE)
            }
        },
    }
}

/// `pipeline forms`: the engine's table of forms as text or JSON.
fn forms_text(json: bool) -> anyhow::Result<String> {
    let forms = &ssbvb_engine::FORMS;
    if json {
        return Ok(serde_json::to_string_pretty(forms)? + "\n");
    }
    let mut out = String::from("SSBVB forms, in the order the rule and the calibration prefer:\n");
    for f in forms {
        let rule = match (f.rule, f.cpu_only) {
            (Some(_), true) => "the rule's choice on CPU adapters",
            (Some(_), false) => "the rule's choice where it fits",
            (None, _) => "only a calibration picks it",
        };
        let calibrated = if f.calibrated { ", calibrated" } else { "" };
        out.push_str(&format!(
            "  {:<18} assets/{:<32} {}; {rule}{calibrated}\n",
            f.name, f.file, f.what
        ));
    }
    Ok(out)
}
