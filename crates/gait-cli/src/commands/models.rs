use std::path::Path;

use crate::error::{CliError, one_line};
use crate::hub;

/// `gait models`: obtain and list model files.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    action: Action,
}

#[derive(Debug, clap::Subcommand)]
enum Action {
    /// Download a model into the models folder (checksums verified)
    Fetch {
        /// Which model: blazepose, hed, openpose, sd15-controlnet-canny
        name: String,
        /// Hugging Face repository to download from [default: the model's usual one; for
        /// sd15-controlnet-canny the Stable Diffusion 1.5 repository]
        #[arg(long, value_name = "ID")]
        repo: Option<String>,
        /// Branch, tag or commit of --repo
        #[arg(long, value_name = "REV", default_value = "main")]
        revision: String,
        /// hed and openpose only: the file's path inside --repo [default: ControlNetHED.pth,
        /// body_pose_model.pth]; it is saved where the stage looks for it
        #[arg(long, value_name = "PATH")]
        file: Option<String>,
        /// sd15-controlnet-canny only: the ControlNet repository [default: lllyasviel/sd-controlnet-canny]
        #[arg(long, value_name = "ID")]
        controlnet_repo: Option<String>,
        /// sd15-controlnet-canny only: branch, tag or commit of --controlnet-repo
        #[arg(long, value_name = "REV", default_value = "main")]
        controlnet_revision: String,
        /// Fetch again even when the files are present (and, for blazepose, check out right)
        #[arg(long)]
        force: bool,
    },
    /// List the models the toolkit knows and whether their files are present
    List,
}

const MODELS: [(&str, &str); 4] = [
    (
        "blazepose",
        "MediaPipe BlazePose full (from the PyPI wheel mediapipe==0.10.14)",
    ),
    (
        "hed",
        "HED edge detector, ControlNetHED.pth (Hugging Face lllyasviel/Annotators)",
    ),
    (
        "openpose",
        "OpenPose body model COCO-18, body_pose_model.pth (Hugging Face lllyasviel/Annotators)",
    ),
    (
        "sd15-controlnet-canny",
        "Stable Diffusion 1.5 + canny ControlNet, diffusers layout (Hugging Face)",
    ),
];

pub fn execute(args: Args, models_dir: &Path) -> Result<(), CliError> {
    match args.action {
        Action::Fetch {
            name,
            repo,
            revision,
            file,
            controlnet_repo,
            controlnet_revision,
            force,
        } => {
            let files = match hub::defaults(&name, models_dir) {
                Some(mut repos) => {
                    if let Some(id) = repo {
                        repos[0].id = id;
                    }
                    repos[0].revision = revision;
                    if let Some(f) = file {
                        if repos.len() != 1 || repos[0].files.len() != 1 {
                            return Err(CliError::new(format!(
                                "--file applies to single-file models (hed, openpose), not `{name}`"
                            )));
                        }
                        repos[0].files[0].0 = f;
                    }
                    match repos.get_mut(1) {
                        Some(cn) => {
                            if let Some(id) = controlnet_repo {
                                cn.id = id;
                            }
                            cn.revision = controlnet_revision;
                        }
                        None if controlnet_repo.is_some() || controlnet_revision != "main" => {
                            return Err(CliError::new(format!(
                                "--controlnet-repo/--controlnet-revision apply to sd15-controlnet-canny only, not `{name}`"
                            )));
                        }
                        None => {}
                    }
                    let present: Vec<_> = repos
                        .iter()
                        .flat_map(|r| &r.files)
                        .map(|(_, dest)| dest)
                        .filter(|d| d.is_file())
                        .collect();
                    if !force && !present.is_empty() {
                        // The Hub's checksums need the network; present files are kept as they are.
                        eprintln!(
                            "{name}: {} file(s) already present, kept (--force downloads them again): {}",
                            present.len(),
                            present
                                .iter()
                                .map(|p| p.display().to_string())
                                .collect::<Vec<_>>()
                                .join(", ")
                        );
                    }
                    hub::fetch(&repos, models_dir, force)
                        .map_err(|e| CliError::new(one_line(&e.to_string())))?
                }
                None if repo.is_some()
                    || file.is_some()
                    || controlnet_repo.is_some()
                    || revision != "main"
                    || controlnet_revision != "main" =>
                {
                    return Err(CliError::new(format!(
                        "`{name}` does not come from the Hugging Face Hub: --repo, --revision, --file and the --controlnet-* options do not apply"
                    )));
                }
                None => fetch_other(&name, models_dir, force)?,
            };
            for f in files {
                eprintln!("{}", f.display());
            }
            Ok(())
        }
        Action::List => {
            println!("models folder: {}", models_dir.display());
            for (name, about) in MODELS {
                let present = present(name, models_dir);
                println!(
                    "{name:<22} {} {about}",
                    if present { "present" } else { "missing" }
                );
            }
            Ok(())
        }
    }
}

fn present(name: &str, models_dir: &Path) -> bool {
    if let Some(repos) = hub::defaults(name, models_dir) {
        return repos
            .iter()
            .flat_map(|r| &r.files)
            .all(|(_, dest)| dest.is_file());
    }
    let ctx = gait_core::StageContext::new(models_dir);
    match name {
        "blazepose" => gait_pose::blazepose::BlazeposeConfig::default()
            .model_files(&ctx)
            .iter()
            .all(|f| f.is_file()),
        _ => false,
    }
}

fn fetch_other(
    name: &str,
    models_dir: &Path,
    force: bool,
) -> Result<Vec<std::path::PathBuf>, CliError> {
    use gait_pose::blazepose::fetch::{Installed, check, fetch};
    match name {
        "blazepose" => {
            if !force {
                match check(models_dir) {
                    Installed::Valid(files) => {
                        eprintln!(
                            "blazepose: present and checked ({} files in {}); nothing fetched (--force fetches them again)",
                            files.len(),
                            models_dir.join("blazepose").display()
                        );
                        return Ok(Vec::new());
                    }
                    Installed::Invalid(why) => eprintln!("blazepose: {why}; fetching again"),
                    Installed::Missing => {}
                }
            }
            fetch(models_dir).map_err(|e| CliError::new(one_line(&e.to_string())))
        }
        other => {
            let known: Vec<&str> = MODELS.iter().map(|(n, _)| *n).collect();
            Err(CliError::new(format!(
                "unknown model `{other}`; known models: {}",
                known.join(", ")
            )))
        }
    }
}
