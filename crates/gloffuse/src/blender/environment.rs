//! The parts of the process environment that finding Blender reads, and the per-user
//! cache directory they imply, as plain data so the search can be tested and reasoned about
//! without touching the real environment.

use std::ffi::OsString;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};

/// The environment variable that names a Blender (like `--blender`).
pub const ENV_VAR: &str = "GLOFFUSE_BLENDER";

/// The bpy series gloffuse provisions, and the pip requirement that selects it.
pub const BPY_SERIES: &str = "4.5";
/// [`BPY_SERIES`] as a version (a test keeps the two equal).
pub const BPY_VERSION: crate::measure::BlenderVersion =
    crate::measure::BlenderVersion { major: 4, minor: 5 };
/// What installing it takes, for the notices (measured with bpy 4.5.x on CPython 3.11).
pub const BPY_SIZE: &str = "a ~370 MB download, ~950 MB installed";
pub const BPY_REQUIREMENT: &str = "bpy>=4.5,<4.6";

#[derive(Clone, Debug, Default)]
pub struct Environment {
    /// `$GLOFFUSE_BLENDER`.
    pub gloffuse_blender: Option<OsString>,
    pub path: Option<OsString>,
    pub xdg_cache_home: Option<OsString>,
    pub home: Option<OsString>,
}

impl Environment {
    pub fn from_process() -> Self {
        Environment {
            gloffuse_blender: std::env::var_os(ENV_VAR),
            path: std::env::var_os("PATH"),
            xdg_cache_home: std::env::var_os("XDG_CACHE_HOME"),
            home: std::env::var_os("HOME"),
        }
    }
}

/// gloffuse's per-user cache: `$XDG_CACHE_HOME/gloffuse`, else `$HOME/.cache/gloffuse`
/// (a relative `XDG_CACHE_HOME` is ignored, as the XDG spec says).
pub fn cache_dir(env: &Environment) -> Option<PathBuf> {
    let set = |v: &Option<OsString>| {
        v.as_ref()
            .filter(|v| Path::new(v).is_absolute())
            .map(PathBuf::from)
    };
    set(&env.xdg_cache_home)
        .or_else(|| set(&env.home).map(|h| h.join(".cache")))
        .map(|c| c.join("gloffuse"))
}

/// Where the bpy venv lives (or would be provisioned): `cache_dir/bpy-4.5`.
pub fn bpy_venv_dir(env: &Environment) -> Option<PathBuf> {
    cache_dir(env).map(|c| c.join(format!("bpy-{BPY_SERIES}")))
}

/// A venv's interpreter.
pub fn venv_python(venv: &Path) -> PathBuf {
    venv.join("bin").join("python")
}

/// The first executable file called `name` in the directories of `path`.
pub fn which(name: &str, path: Option<&std::ffi::OsStr>) -> Option<PathBuf> {
    std::env::split_paths(path?)
        .filter(|d| !d.as_os_str().is_empty())
        .map(|d| d.join(name))
        .find(|p| {
            std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
        })
}

/// Why the venv at `venv` can no longer run, if it cannot: its Python was moved or removed
/// (as after a CI image update) — `bin/python` missing or a dangling link, or the base
/// interpreter `pyvenv.cfg` names (`executable`, else `home`) gone. A working venv, or one
/// that cannot be judged without running it, gives `None`.
pub fn broken_venv(venv: &Path) -> Option<String> {
    let python = venv_python(venv);
    if std::fs::symlink_metadata(&python).is_err() {
        return Some(format!("{} is missing", python.display()));
    }
    if std::fs::metadata(&python).is_err() {
        let target = std::fs::read_link(&python).unwrap_or_default();
        return Some(format!(
            "{} is a dangling link (to {})",
            python.display(),
            target.display()
        ));
    }
    let cfg = std::fs::read_to_string(venv.join("pyvenv.cfg")).ok()?;
    let value = |key: &str| {
        cfg.lines().find_map(|l| {
            let (k, v) = l.split_once('=')?;
            (k.trim() == key).then(|| v.trim().to_string())
        })
    };
    let (key, base) = match value("executable") {
        Some(e) => ("executable", e),
        None => ("home", value("home")?),
    };
    (!Path::new(&base).exists()).then(|| {
        format!(
            "its pyvenv.cfg names {key} = {base}, which no longer exists (the Python it was \
             made with has moved)"
        )
    })
}
