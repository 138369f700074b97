//! `gloffuse farm slurm|openjd`: the job checked here (paths, audit flags, folder), its files
//! made by `jobs` (the command lines of gloffuse itself, so they live with its flags), and
//! with `slurm --submit` the two `sbatch` calls.

mod jobs;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use clap::Parser;
use gloffuse::output::{make_report_dir, write_output};
use gloffuse::{Error, Field, Hint};

use crate::cli::args::{Cli, Command as Cmd, FarmArgs, SlurmArgs};
use crate::cli::progress::eprintln_quietly;
use crate::cli::{Outcome, Result, print_json};
use jobs::{FarmJob, MERGED, SlurmJob, openjd, slurm};

/// The flags the farm sets on every shard itself.
const FARM_FLAGS: &str = "--shard, --report, --junit, --sarif, --json or --exit-zero";

/// The job `a` describes, checked: the paths hold .blend files and the audit flags parse.
fn job(a: &FarmArgs) -> Result<FarmJob> {
    gloffuse::audit::files::blend_files(&a.paths)?;
    let audit_line = ["gloffuse", "audit"]
        .into_iter()
        .map(String::from)
        .chain(a.audit_flags.iter().cloned())
        .chain(std::iter::once("--".to_string()))
        .chain(a.paths.iter().map(|p| p.display().to_string()));
    let bad_flags = |why: String| {
        Error::input(
            Field::Arguments,
            a.audit_flags.join(" "),
            Hint::text(format!("`gloffuse audit` flags after -- ({why})")),
        )
    };
    match Cli::try_parse_from(audit_line) {
        Ok(Cli {
            command: Cmd::Audit(audit),
            ..
        }) => {
            if audit.shard.is_some()
                || audit.report.is_some()
                || audit.junit.is_some()
                || audit.sarif.is_some()
                || audit.json
                || audit.exit_zero
            {
                return Err(bad_flags(format!("the farm sets {FARM_FLAGS} itself")).into());
            }
        }
        Ok(_) => unreachable!("the line starts with `audit`"),
        Err(e) => {
            let first = e.to_string().lines().next().unwrap_or_default().to_string();
            return Err(bad_flags(first.trim_start_matches("error: ").to_string()).into());
        }
    }
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let program = match &a.gloffuse {
        // A path (with a `/`) is made absolute as the others are: a node runs it from
        // another folder. A bare name stays a command the nodes find on their PATH.
        Some(p) if p.contains('/') => absolute(Path::new(p)).display().to_string(),
        Some(p) => p.clone(),
        None => std::env::current_exe()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|_| "gloffuse".into()),
    };
    Ok(FarmJob {
        program,
        paths: a.paths.iter().map(|p| absolute(p)).collect(),
        audit_flags: a.audit_flags.clone(),
        shards: a.shards as usize,
        dir: absolute(&a.out),
        workdir: std::env::current_dir().unwrap_or_else(|_| PathBuf::from("/")),
    })
}

/// `farm openjd`: the template and its parameters' values, written into the job's folder.
pub fn openjd_template(a: &FarmArgs, out: &mut dyn Write) -> Result<Outcome> {
    let job = job(a)?;
    let j = openjd(&job)?;
    make_report_dir(&job.dir)?;
    let template = job.dir.join("gloffuse-audit.template.json");
    let parameters = job.dir.join("parameters.json");
    for (path, value) in [(&template, &j.template), (&parameters, &j.parameters)] {
        let text = serde_json::to_string_pretty(value).expect("JSON values serialise");
        write_output(path, format!("{text}\n").as_bytes())?;
        eprintln_quietly(&format!("wrote {}", path.display()));
    }
    let quote = |p: &Path| gloffuse::blender::process::shell_quote(p.as_os_str());
    writeln!(
        out,
        "run it: openjd run {} -p file://{}\n(the merged report will be in {})",
        quote(&template),
        parameters.display(),
        job.dir.join(MERGED).display()
    )?;
    Ok(Outcome::Success)
}

/// `farm slurm`: the scripts, and with `--submit` the array job and its merge job.
pub fn slurm_job(a: &SlurmArgs, out: &mut dyn Write) -> Result<Outcome> {
    let job = job(&a.farm)?;
    if job.dir.as_os_str().as_encoded_bytes().contains(&b'\\') {
        // Slurm reads a log path holding a backslash without its `%a` and drops the
        // backslashes: the logs would land elsewhere, all in one file.
        return Err(Error::input(
            Field::Out,
            job.dir.display(),
            "a folder with no backslash in its path (Slurm's --output gives them a meaning)",
        )
        .into());
    }
    let s = slurm(&job, &a.sbatch_arg);
    make_report_dir(&job.dir)?;
    make_report_dir(&job.dir.join("logs"))?;
    for (name, text) in [
        ("audit.sh", &s.audit_script),
        ("merge.sh", &s.merge_script),
        ("submit.sh", &s.submit_script),
    ] {
        let path = job.dir.join(name);
        write_output(&path, text.as_bytes())?;
        executable(&path)?;
        eprintln_quietly(&format!("wrote {}", path.display()));
    }
    if !a.submit {
        writeln!(out, "submit it: {}", job.dir.join("submit.sh").display())?;
        return Ok(Outcome::Success);
    }
    let (audit, merge) = submit(&s)?;
    let merged = job.dir.join(MERGED);
    if a.json {
        let ids = serde_json::json!({"audit_job": audit, "merge_job": merge, "shards": job.shards,
                                     "dir": job.dir, "merged": merged});
        print_json(out, &ids)?;
    } else {
        writeln!(
            out,
            "submitted: audit array job {audit} ({}), merge job {merge}; the merged report \
             will be in {}",
            gloffuse::plural::count(job.shards, "shard", "shards"),
            merged.display()
        )?;
    }
    Ok(Outcome::Success)
}

fn executable(path: &Path) -> Result<()> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).map_err(|e| {
        Error::Write {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
        .into()
    })
}

/// Submits the array job, then the merge job after it: their ids.
fn submit(s: &SlurmJob) -> Result<(String, String)> {
    let audit = sbatch(&s.audit_sbatch)?;
    let mut merge_args = vec![format!("--dependency=afterany:{audit}")];
    merge_args.extend(s.merge_sbatch.iter().cloned());
    let merge = sbatch(&merge_args)?;
    Ok((audit, merge))
}

/// Runs `sbatch --parsable …`: the job id it prints (without a cluster name).
fn sbatch(args: &[String]) -> Result<String> {
    let failed = |message: String| {
        Error::Blender {
            message: Hint::text(format!("sbatch {}: {message}", args.join(" "))),
            log: None,
            command: None,
        }
        .into()
    };
    let output = Command::new("sbatch")
        .args(args)
        .output()
        .map_err(|e| failed(format!("{e} (is Slurm's sbatch on PATH?)")))?;
    let text = String::from_utf8_lossy(&output.stdout);
    let id = text
        .trim()
        .split(';')
        .next()
        .unwrap_or_default()
        .to_string();
    if !output.status.success() || id.is_empty() {
        return Err(failed(format!(
            "{} {}",
            output.status,
            String::from_utf8_lossy(&output.stderr).trim()
        )));
    }
    Ok(id)
}
