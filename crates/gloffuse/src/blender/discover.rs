//! Finding a Blender to run: a `blender` executable, or a Python interpreter that imports
//! `bpy` (Blender as a Python module), and, when there is none, installing bpy 4.5 LTS into
//! a per-user cache.
//!
//! Search order ([`find_blender`]): `--blender PATH`, then `$GLOFFUSE_BLENDER`, then
//! `blender` on `PATH`, then the bpy venv provisioned earlier in
//! `$XDG_CACHE_HOME/gloffuse/bpy-4.5` (else `~/.cache/gloffuse/bpy-4.5`), then — if allowed —
//! provisioning that venv. A path the user named (flag or variable) is used or refused,
//! never silently passed over.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use super::environment::{BPY_SERIES, ENV_VAR, Environment, bpy_venv_dir, venv_python, which};
use super::probe::{Blender, BlenderKind, PROBE_TIMEOUT, Source, probe_as};
use super::process::Cancel;
use super::provision::{InstallerOutput, provision};
use crate::error::{Error, Field, Hint};
use crate::progress::Progress;

#[derive(Clone, Debug)]
pub struct FindOptions {
    /// From `--blender PATH`: a blender executable, or a Python that imports bpy.
    pub explicit: Option<PathBuf>,
    /// Install bpy into the cache when nothing else is found (off with `--no-provision`).
    pub allow_provision: bool,
    /// Where pip's output goes while provisioning.
    pub installer_output: InstallerOutput,
    /// The whole search (every version probe) ends within this; installing bpy is not
    /// bounded by it.
    pub timeout: Duration,
    /// Stops a probe or an install in progress.
    pub cancel: Cancel,
}

impl Default for FindOptions {
    fn default() -> Self {
        FindOptions {
            explicit: None,
            allow_provision: false,
            installer_output: InstallerOutput::default(),
            timeout: PROBE_TIMEOUT,
            cancel: Cancel::default(),
        }
    }
}

/// One step of the search.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// Probe this program; `required`: if it does not work, fail (the user named it)
    /// rather than go on.
    Probe {
        source: Source,
        program: PathBuf,
        kind: Option<BlenderKind>,
        required: bool,
    },
    /// Nothing there: say so in the not-found message.
    Absent { place: String },
    /// Install bpy into this venv directory (if provisioning is allowed).
    Provision { venv: PathBuf },
}

/// The search, in order, as far as it can be decided without running anything.
///
/// `--blender` and `$GLOFFUSE_BLENDER` each end the search: what the user named is used or
/// refused. Otherwise: `blender` on PATH, the cached venv if it exists, else provisioning.
pub fn search_plan(opts: &FindOptions, env: &Environment) -> Vec<Step> {
    if let Some(p) = &opts.explicit {
        return vec![Step::Probe {
            source: Source::Explicit,
            program: p.clone(),
            kind: None,
            required: true,
        }];
    }
    if let Some(p) = env.gloffuse_blender.as_ref().filter(|p| !p.is_empty()) {
        return vec![Step::Probe {
            source: Source::EnvVar,
            program: PathBuf::from(p),
            kind: None,
            required: true,
        }];
    }
    let mut plan = vec![Step::Absent {
        place: format!("{ENV_VAR}: not set"),
    }];
    plan.push(match which("blender", env.path.as_deref()) {
        Some(program) => Step::Probe {
            source: Source::SystemPath,
            program,
            kind: Some(BlenderKind::Binary),
            required: false,
        },
        None => Step::Absent {
            place: "`blender` on PATH: not found".into(),
        },
    });
    match bpy_venv_dir(env) {
        Some(venv) if venv.exists() => plan.push(Step::Probe {
            source: Source::Cache,
            program: venv_python(&venv),
            kind: Some(BlenderKind::PythonModule),
            // A venv there was complete when it was renamed into place; if it no longer
            // works, say so rather than install a second copy over it.
            required: true,
        }),
        Some(venv) => {
            plan.push(Step::Absent {
                place: format!("bpy cache {}: not provisioned", venv.display()),
            });
            plan.push(Step::Provision { venv });
        }
        None => plan.push(Step::Absent {
            place: "bpy cache: none (neither XDG_CACHE_HOME nor HOME is set)".into(),
        }),
    }
    plan
}

/// Finds a Blender, as described in the module docs, in the process's own environment.
/// Provisioning announces itself through `progress`.
pub fn find_blender(opts: &FindOptions, progress: &dyn Progress) -> Result<Blender, Error> {
    find_blender_in(opts, &Environment::from_process(), progress)
}

/// [`find_blender`] in the given environment.
pub fn find_blender_in(
    opts: &FindOptions,
    env: &Environment,
    progress: &dyn Progress,
) -> Result<Blender, Error> {
    // Every place looked at, for the not-found message; the candidates that were there but
    // could not be used, for the provisioning notice.
    let mut looked: Vec<Hint> = Vec::new();
    let mut skipped: Vec<Hint> = Vec::new();
    let deadline = Instant::now() + opts.timeout;
    for step in search_plan(opts, env) {
        match step {
            Step::Absent { place } => looked.push(Hint::text(place)),
            Step::Probe {
                source,
                program,
                kind,
                required,
            } => match probe_as(&program, kind, source, deadline, &opts.cancel) {
                Ok(b) => return Ok(b),
                Err(e) if required => return Err(e),
                Err(e) => {
                    let why = source
                        .hint()
                        .then(Hint::text(format!(" ({}): ", program.display())))
                        .then(e.hint());
                    looked.push(why.clone());
                    skipped.push(why);
                }
            },
            Step::Provision { venv } if opts.allow_provision => {
                return provision(
                    &venv,
                    env,
                    opts.installer_output,
                    &skipped,
                    progress,
                    &opts.cancel,
                );
            }
            Step::Provision { .. } => {}
        }
    }
    Err(not_found(&looked))
}

fn not_found(looked: &[Hint]) -> Error {
    let mut m = Hint::text("no Blender found. gloffuse looked at:");
    for l in looked {
        m = m.then(Hint::text("\n  - ")).then(l.clone());
    }
    let advice = Hint::new(
        format!(
            "\nPoint it at one with {{}} PATH or {ENV_VAR}=PATH (a blender executable, or a \
             Python that imports bpy), install one (apt-get install blender), or drop {{}} to \
             let gloffuse install bpy {BPY_SERIES} LTS (~370 MB) into its cache."
        ),
        [Field::Blender, Field::NoProvision],
    );
    Error::BlenderNotFound(m.then(advice))
}
