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

use super::environment::{
    BPY_SERIES, BPY_SIZE, ENV_VAR, Environment, bpy_venv_dir, broken_venv, venv_python, which,
};
use super::probe::{Blender, BlenderKind, PROBE_TIMEOUT, Source, probe_as};
use super::process::Cancel;
use super::provision::{InstallerOutput, provision};
use crate::error::{Error, Field, Hint};
use crate::measure::BlenderVersion;
use crate::progress::Progress;

/// The oldest Blender a job can use, the input that asks for that job, and why (e.g. an
/// extension needs 4.2). A Blender found on PATH that is older is passed over for the bpy
/// cache or a provisioned bpy; one the user named is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Need {
    pub version: BlenderVersion,
    pub by: Field,
    pub why: &'static str,
}

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
    /// The oldest Blender the job can use, if it cannot use every one gloffuse runs.
    pub need: Option<Need>,
}

impl Default for FindOptions {
    fn default() -> Self {
        FindOptions {
            explicit: None,
            allow_provision: false,
            installer_output: InstallerOutput::default(),
            timeout: PROBE_TIMEOUT,
            cancel: Cancel::default(),
            need: None,
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
    /// The venv there is broken (`why`): replace it by a fresh install if provisioning is
    /// allowed, else fail saying how to remove it.
    Repair { venv: PathBuf, why: String },
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
        Some(venv) if venv.exists() => plan.push(match broken_venv(&venv) {
            Some(why) => Step::Repair { venv, why },
            None => Step::Probe {
                source: Source::Cache,
                program: venv_python(&venv),
                kind: Some(BlenderKind::PythonModule),
                // A venv there was complete when it was renamed into place; if it no longer
                // works, say so rather than install a second copy over it.
                required: true,
            },
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
    let mut search = Search::default();
    let deadline = Instant::now() + opts.timeout;
    let provision_into = |venv: &PathBuf, broken: Option<&str>, skipped: &[Hint]| {
        let b = provision(
            venv,
            env,
            opts.installer_output,
            skipped,
            broken,
            progress,
            &opts.cancel,
        );
        b.map(|b| (b, Source::Cache, true))
    };
    for step in search_plan(opts, env) {
        let (found, source, required) = match step {
            Step::Absent { place } => {
                search.looked.push(Hint::text(place));
                continue;
            }
            Step::Probe {
                source,
                program,
                kind,
                required,
            } => match probe_as(&program, kind, source, deadline, &opts.cancel) {
                Ok(b) => (b, source, required),
                Err(e) if required && source == Source::Cache => {
                    return Err(with_removal_advice(e, &program));
                }
                Err(e) if required => return Err(e),
                Err(e) => {
                    search.skip(source, &program, e.hint(), false);
                    continue;
                }
            },
            Step::Provision { venv } if opts.allow_provision => {
                provision_into(&venv, None, &search.skipped)?
            }
            Step::Provision { .. } => continue,
            Step::Repair { venv, why } if opts.allow_provision => {
                provision_into(&venv, Some(&why), &search.skipped)
                    .map_err(|e| with_removal_advice(e, &venv_python(&venv)))?
            }
            Step::Repair { venv, why } => return Err(broken_cache(&venv, &why)),
        };
        match opts.need.filter(|n| found.version < n.version) {
            None => {
                search.announce_older(progress);
                return Ok(found);
            }
            Some(need) if required => return Err(too_old(&found, source, need)),
            Some(need) => {
                let why = Hint::new(
                    format!(
                        "Blender {} is older than {}.{}, which {{}} needs ({})",
                        found.version_string, need.version.major, need.version.minor, need.why
                    ),
                    [need.by],
                );
                search.skip(source, &found.program, why, true);
            }
        }
    }
    Err(match opts.need {
        Some(need) if !search.older.is_empty() => none_new_enough(need, &search.looked),
        _ => not_found(&search.looked),
    })
}

/// What a search saw on its way: every place looked at (for the not-found message), the
/// candidates that were there but could not be used (for the provisioning notice), and of
/// those the ones too old for the job (announced when a newer one is used).
#[derive(Default)]
struct Search {
    looked: Vec<Hint>,
    skipped: Vec<Hint>,
    older: Vec<Hint>,
}

impl Search {
    fn skip(&mut self, source: Source, program: &std::path::Path, why: Hint, older: bool) {
        let why = source
            .hint()
            .then(Hint::text(format!(" ({}): ", program.display())))
            .then(why);
        self.looked.push(why.clone());
        self.skipped.push(why.clone());
        if older {
            self.older.push(why);
        }
    }

    /// Says which Blenders were passed over as too old for the job, so a user who expected
    /// the one on PATH knows why another runs.
    fn announce_older(&self, progress: &dyn Progress) {
        for o in &self.older {
            progress.advise(&Hint::text("not using ").then(o.clone()));
        }
    }
}

/// The Blender the user named (`source`) is older than the job needs: say which input
/// named it and what would do.
fn too_old(found: &Blender, source: Source, need: Need) -> Error {
    let wanted = format!("{}.{}", need.version.major, need.version.minor);
    match source {
        Source::Explicit => Error::input(
            Field::Blender,
            format!("Blender {}", found.version_string),
            Hint::new(
                format!("Blender {wanted} or later for {{}} ({})", need.why),
                [need.by],
            ),
        ),
        _ => Error::BlenderNotFound(
            source
                .hint()
                .then(Hint::new(
                    format!(
                        " names {}, older than {wanted}, which {{}} needs ({}). Point it at \
                         Blender {wanted} or later",
                        found.describe(),
                        need.why
                    ),
                    [need.by],
                ))
                .then(Hint::text(if source == Source::EnvVar {
                    format!(", or unset {ENV_VAR} to let gloffuse choose one.")
                } else {
                    ".".into()
                })),
        ),
    }
}

/// Blenders were found, but none new enough, and none may be installed.
fn none_new_enough(need: Need, looked: &[Hint]) -> Error {
    let wanted = format!("{}.{}", need.version.major, need.version.minor);
    let mut m = Hint::new(
        format!("no Blender {wanted} or later, which {{}} needs, was found. gloffuse looked at:"),
        [need.by],
    );
    for l in looked {
        m = m.then(Hint::text("\n  - ")).then(l.clone());
    }
    Error::BlenderNotFound(m.then(Hint::new(
        format!(
            "\n{{}} forbids installing bpy {BPY_SERIES} LTS, which would do: drop it to let \
             gloffuse install bpy into its cache ({BPY_SIZE}), or set {ENV_VAR} to a Blender \
             {wanted} or later (a blender executable, or a Python that imports bpy)."
        ),
        [Field::NoProvision],
    )))
}

/// The cached venv is broken and may not be reinstalled: name it and the fix.
fn broken_cache(venv: &std::path::Path, why: &str) -> Error {
    Error::BlenderNotFound(
        Hint::text(format!(
            "the cached bpy {BPY_SERIES} at {} is broken: {why}.",
            venv.display()
        ))
        .then(removal_advice(venv))
        .then(Hint::new(
            " Or drop {} to let gloffuse reinstall it now.",
            [Field::NoProvision],
        )),
    )
}

/// How to remove a broken cached venv so gloffuse installs it afresh.
fn removal_advice(venv: &std::path::Path) -> Hint {
    Hint::text(format!(
        "\nRemove it with: rm -rf {}\n(gloffuse installs bpy {BPY_SERIES} there again when \
         it next needs it; {BPY_SIZE}.)",
        super::process::shell_quote(venv.as_os_str())
    ))
}

/// A cached venv at `python`'s venv failed (its probe, or its repair): the error, and how
/// to remove the venv.
fn with_removal_advice(e: Error, python: &std::path::Path) -> Error {
    // A repair that failed after removing the venv needs no advice: the next run installs.
    let Some(venv) = python
        .parent()
        .and_then(|bin| bin.parent())
        .filter(|v| v.symlink_metadata().is_ok())
    else {
        return e;
    };
    match e {
        Error::BlenderNotFound(m) => Error::BlenderNotFound(m.then(removal_advice(venv))),
        Error::Blender {
            message,
            log,
            command,
        } => Error::Blender {
            message: message.then(removal_advice(venv)),
            log,
            command,
        },
        other => other,
    }
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
             let gloffuse install bpy {BPY_SERIES} LTS ({BPY_SIZE}) into its cache."
        ),
        [Field::Blender, Field::NoProvision],
    );
    Error::BlenderNotFound(m.then(advice))
}
