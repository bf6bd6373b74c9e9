use std::path::Path;

use crate::commands::PipelineArgs;
use crate::error::CliError;

/// `gait edges`: write the edge map of every frame as a PNG (named by frame
/// index) into the output folder; the config's [edge] and [input] tables apply.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pipeline: PipelineArgs,
}

pub fn execute(args: Args, models_dir: &Path) -> Result<(), CliError> {
    let p = &args.pipeline;
    let config = p.config()?;
    let n =
        gait_pipeline::edges::export_edges(&config, &p.input, &p.out, models_dir, !p.no_progress)?;
    eprintln!("{n} edge maps -> {}", p.out.display());
    Ok(())
}
