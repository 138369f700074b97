//! The library's one error type. Every variant names the input or file that was wrong and,
//! where it can, what would be right. The physics' own error (a value out of a BSDF's range)
//! becomes an [`Error::Input`] of the field that carried the value.

use std::path::PathBuf;

use gloffuse_physics::Quantity;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A value given to the library is not acceptable. `field` names it in the library's
    /// terms; the CLI names the flag that sets it instead (see [`Error::render`]).
    #[error("{}", self.hint())]
    Input {
        field: Field,
        value: String,
        expected: Hint,
    },

    /// A fit cannot be made from the points given.
    #[error("cannot fit: {0}")]
    Fit(String),

    /// A coefficients file (or preset name) is malformed or inconsistent.
    #[error("coefficients {source_name}: {message}")]
    Coefficients {
        source_name: String,
        message: String,
    },

    /// The io error is the cause (`source()`); the CLI prints the chain in full.
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },

    #[error("cannot write {}: {message}", path.display())]
    Write { path: PathBuf, message: String },

    /// A Blender (or bpy) was found but could not be used, or a run in it failed. `log` is
    /// the file that holds its output; `command` the shell-quoted command to rerun it.
    #[error("{}", self.hint())]
    Blender {
        message: Hint,
        log: Option<PathBuf>,
        command: Option<String>,
    },

    /// A rendered EXR could not be read back.
    #[error(transparent)]
    Exr(#[from] ExrError),

    /// No usable Blender: the message says where gloffuse looked and how to point at one.
    #[error("{}", self.hint())]
    BlenderNotFound(Hint),

    /// The user stopped the command (Ctrl-C, SIGTERM): Blender was stopped, temporary files
    /// removed, and nothing written but the files in `written` (each whole, replaced before
    /// the stop).
    #[error("{}", interrupted_text(log.as_deref(), written))]
    Interrupted {
        log: Option<PathBuf>,
        written: Vec<PathBuf>,
    },
}

/// What a stop says: what was written before it (every such file complete), or that nothing
/// was.
fn interrupted_text(log: Option<&std::path::Path>, written: &[PathBuf]) -> String {
    let log = log
        .map(|l| format!(" (its log: {})", l.display()))
        .unwrap_or_default();
    if written.is_empty() {
        return format!("interrupted: Blender was stopped and nothing was written{log}");
    }
    let files: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    format!(
        "interrupted: Blender was stopped{log}; before the stop, gloffuse had written {} \
         (each complete; a replaced file's previous version is its .blend1): {}",
        if written.len() == 1 {
            "1 file".to_string()
        } else {
            format!("{} files", written.len())
        },
        files.join(", ")
    )
}

/// A one-line message gets `; log: …; command: …` appended; a multi-line one (quoted
/// output) gets them on lines of their own, so the path and command are easy to copy.
fn blender_hint(message: &Hint, log: Option<&std::path::Path>, command: Option<&str>) -> Hint {
    let sep = if message.to_string().contains('\n') {
        "\n  "
    } else {
        "; "
    };
    let mut s = message.clone().trim_end();
    if let Some(log) = log {
        s = s.then(Hint::text(format!("{sep}log: {}", log.display())));
    }
    if let Some(command) = command {
        s = s.then(Hint::text(format!("{sep}command: {command}")));
    }
    s
}

impl Error {
    /// `field` was given as `value`; `expected` says what would be right.
    pub fn input(field: Field, value: impl ToString, expected: impl Into<Hint>) -> Self {
        Error::Input {
            field,
            value: value.to_string(),
            expected: expected.into(),
        }
    }

    /// The message, with each field named by `name`: [`Field::name`] in the library's own
    /// words (the `Display` text), a flag where the CLI renders it.
    pub fn render(&self, name: impl Fn(Field) -> String) -> String {
        self.hint().render(name)
    }

    /// The message as a [`Hint`], its fields still unnamed.
    pub fn hint(&self) -> Hint {
        match self {
            Error::Input {
                field,
                value,
                expected,
            } => Hint::new("invalid {}", [*field])
                .then(Hint::text(format!(" '{value}': expected ")))
                .then(expected.clone()),
            Error::Blender {
                message,
                log,
                command,
            } => blender_hint(message, log.as_deref(), command.as_deref()),
            Error::BlenderNotFound(message) => message.clone(),
            other => Hint::text(other.to_string()),
        }
    }
}

impl From<gloffuse_physics::Error> for Error {
    fn from(e: gloffuse_physics::Error) -> Self {
        Error::input(Field::from(e.quantity), e.value, e.expected)
    }
}

/// An input of a library call, in the library's own terms. The library never spells a
/// command-line flag: the CLI maps each field to the flag that sets it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    /// The combination of inputs as a whole (none of them alone is wrong).
    Arguments,
    /// The Anisotropy input of a Glossy BSDF.
    Anisotropy,
    /// The Blender to run: an executable, or a Python that imports bpy.
    Blender,
    /// The Blender version whose BSDFs are modelled.
    BlenderVersion,
    /// The .blend library to write.
    Blend,
    /// The asset catalog definition file beside a library (`blender_assets.cats.txt`).
    Catalogs,
    Coefficients,
    Color,
    /// What a coloured correction keeps (exact or physical).
    ColorModel,
    /// The geometry of a contact sheet of renders.
    ContactSheet,
    /// The degree of a fitted polynomial.
    Degree,
    Distribution,
    Engine,
    /// The Blender extension (.zip) to write.
    Extension,
    /// The classic add-on (.zip) to write.
    Addon,
    /// Replace an existing file that is not what a command would replace unasked (a
    /// library .blend that is not a gloffuse library).
    Force,
    /// A table's file format.
    Format,
    /// The masking function of a split-sum table.
    GModel,
    /// The user's existing .blend to update in place.
    Into,
    /// Whether a file saved by a newer Blender may be opened and saved by an older one.
    AllowDowngrade,
    /// A .blend file or folder to audit.
    AuditPath,
    /// An audit configuration file (`gloffuse.toml`).
    AuditConfig,
    /// An earlier audit report to compare with.
    Baseline,
    /// The only audit rules that run.
    Select,
    /// Audit rules that do not run.
    Ignore,
    /// Which audit verdicts fail the check.
    FailOn,
    /// The fixed copy of one audited .blend to write.
    Fix,
    /// The folder for fixed copies of every audited .blend.
    FixDir,
    /// Fix the audited .blend files themselves.
    InPlace,
    /// Indices of refraction.
    Ior,
    /// Where a fit's points come from (the integrator, rather than points given).
    FitSource,
    /// Which lookup table.
    Kind,
    /// How a split-sum table is integrated.
    Method,
    /// The correction mode.
    Mode,
    /// A classic BRDF model.
    Model,
    /// The setting that forbids installing bpy when no Blender is found.
    NoProvision,
    /// A parameter of a classic BRDF model, named as the model names it.
    ModelParameter(&'static str),
    /// The file to write.
    Out,
    /// A measured point ROUGHNESS:PERCENT, its roughness, its percent.
    Point,
    PointRoughness,
    PointPercent,
    /// The report directory.
    Report,
    /// Which part of a sharded run to do (K of N).
    Shard,
    /// A shard's report, to merge.
    ShardReport,
    Roughness,
    Samples,
    /// The Python script to write.
    Script,
    /// Texels per side.
    Size,
    /// The CSV file for a grid of albedos.
    Table,
    /// How long Blender may run.
    Timeout,
    /// A view cosine μ.
    ViewCosine,
}

impl Field {
    /// The field in words, as the library's own messages name it.
    pub fn name(self) -> String {
        match self {
            Field::Arguments => "arguments",
            Field::Anisotropy => "anisotropy",
            Field::Blender => "blender",
            Field::BlenderVersion => "Blender version",
            Field::Blend => "library .blend",
            Field::Catalogs => "asset catalog file",
            Field::Coefficients => "coefficients",
            Field::Color => "colour",
            Field::ColorModel => "colour model",
            Field::ContactSheet => "contact sheet",
            Field::Degree => "degree",
            Field::Distribution => "distribution",
            Field::Engine => "engine",
            Field::Extension => "extension",
            Field::Addon => "add-on",
            Field::Force => "force",
            Field::Format => "format",
            Field::GModel => "masking model",
            Field::Into => "file to update",
            Field::AllowDowngrade => "permission to downgrade the file",
            Field::AuditPath => "path to audit",
            Field::AuditConfig => "audit configuration",
            Field::Baseline => "baseline report",
            Field::Select => "rules to run",
            Field::Ignore => "rules to skip",
            Field::FailOn => "verdicts that fail",
            Field::Fix => "fixed copy",
            Field::FixDir => "folder for fixed copies",
            Field::InPlace => "in-place fix",
            Field::Ior => "index of refraction",
            Field::FitSource => "fit source",
            Field::Kind => "table kind",
            Field::Method => "method",
            Field::Mode => "mode",
            Field::Model => "model",
            Field::ModelParameter(name) => name,
            Field::Out => "output",
            Field::NoProvision => "no-provision",
            Field::Point => "point",
            Field::PointRoughness => "point roughness",
            Field::PointPercent => "point percent",
            Field::Report => "report directory",
            Field::Shard => "shard",
            Field::ShardReport => "shard report",
            Field::Roughness => "roughness",
            Field::Samples => "samples",
            Field::Script => "script",
            Field::Size => "size",
            Field::Table => "albedo table",
            Field::Timeout => "timeout",
            Field::ViewCosine => "view cosine mu",
        }
        .to_string()
    }
}

impl From<Quantity> for Field {
    fn from(quantity: Quantity) -> Self {
        match quantity {
            Quantity::Anisotropy => Field::Anisotropy,
            Quantity::BlenderVersion => Field::BlenderVersion,
            Quantity::Distribution => Field::Distribution,
            Quantity::Engine => Field::Engine,
            Quantity::Model => Field::Model,
            Quantity::ModelParameter(name) => Field::ModelParameter(name),
            Quantity::Roughness => Field::Roughness,
            Quantity::ViewCosine => Field::ViewCosine,
        }
    }
}

/// Text that may name fields: what an input should have been, or a message that tells the
/// user which input to change.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Hint(Vec<Piece>);

#[derive(Clone, Debug, PartialEq, Eq)]
enum Piece {
    Text(String),
    Field(Field),
}

impl Hint {
    /// `Hint::new("nothing with {} coat", [Field::Kind])`: each `{}` in the template stands
    /// for the next field. Text from elsewhere (a log, a path) goes in by [`Hint::text`].
    pub fn new(template: impl AsRef<str>, fields: impl IntoIterator<Item = Field>) -> Self {
        let template = template.as_ref();
        let mut fields = fields.into_iter();
        let mut pieces = Vec::new();
        for (i, text) in template.split("{}").enumerate() {
            if i > 0 {
                let field = fields.next().expect("a hint has a field for every {}");
                pieces.push(Piece::Field(field));
            }
            pieces.push(Piece::Text(text.to_string()));
        }
        debug_assert!(fields.next().is_none(), "a hint has a {{}} for every field");
        Hint(pieces)
    }

    /// Plain text, taken as it is.
    pub fn text(text: impl Into<String>) -> Self {
        Hint(vec![Piece::Text(text.into())])
    }

    /// Without trailing white space.
    fn trim_end(mut self) -> Self {
        while let Some(Piece::Text(text)) = self.0.last_mut() {
            let kept = text.trim_end().len();
            text.truncate(kept);
            if !text.is_empty() {
                break;
            }
            self.0.pop();
        }
        self
    }

    /// This hint followed by `more`.
    pub fn then(mut self, more: Hint) -> Self {
        self.0.extend(more.0);
        self
    }

    /// The text with each field named by `name`.
    pub fn render(&self, name: impl Fn(Field) -> String) -> String {
        self.0
            .iter()
            .map(|piece| match piece {
                Piece::Text(text) => text.clone(),
                Piece::Field(field) => name(*field),
            })
            .collect()
    }
}

impl From<&str> for Hint {
    fn from(text: &str) -> Self {
        Hint::text(text)
    }
}

impl From<String> for Hint {
    fn from(text: String) -> Self {
        Hint::text(text)
    }
}

impl std::fmt::Display for Hint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.render(Field::name))
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Why an EXR could not be used; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ExrError {
    #[error("EXR {} does not exist (Blender did not write it; see the log)", path.display())]
    Missing { path: PathBuf },
    #[error("EXR {} is truncated or corrupt: {why}", path.display())]
    Corrupt { path: PathBuf, why: String },
    #[error("EXR {} uses a feature gloffuse cannot read ({why}); write single-layer OPEN_EXR, 32-bit float, ZIP", path.display())]
    Unsupported { path: PathBuf, why: String },
    #[error("EXR {} has no {channel} channel (found: {found}); gloffuse needs R, G, B and A", path.display())]
    MissingChannel {
        path: PathBuf,
        channel: &'static str,
        found: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(field: Field) -> String {
        format!("--{}", field.name().replace(' ', "-"))
    }

    #[test]
    fn a_hint_names_each_field_as_the_caller_says() {
        let hint = Hint::new(
            "nothing with {} split-sum ({} applies)",
            [Field::Kind, Field::Method],
        );
        assert_eq!(
            hint.to_string(),
            "nothing with table kind split-sum (method applies)"
        );
        assert_eq!(
            hint.render(flags),
            "nothing with --table-kind split-sum (--method applies)"
        );
    }

    #[test]
    fn text_from_elsewhere_is_taken_as_it_is() {
        let hint = Hint::text("a path {} with braces").then(Hint::new(" see {}", [Field::Out]));
        assert_eq!(hint.render(flags), "a path {} with braces see --output");
    }

    #[test]
    fn an_input_error_names_its_field_and_what_was_expected() {
        let e = Error::input(Field::Ior, 1.5, Hint::new("{} layered", [Field::Mode]));
        assert_eq!(
            e.to_string(),
            "invalid index of refraction '1.5': expected mode layered"
        );
        assert_eq!(
            e.render(flags),
            "invalid --index-of-refraction '1.5': expected --mode layered"
        );
    }

    #[test]
    fn a_physics_error_becomes_the_input_error_of_its_field() {
        let physics = "2"
            .parse::<gloffuse_physics::measure::Roughness>()
            .unwrap_err();
        let e = Error::from(physics.clone());
        assert!(matches!(
            e,
            Error::Input {
                field: Field::Roughness,
                ..
            }
        ));
        // The same words as the physics says them, and the flag where the CLI names it.
        assert_eq!(e.to_string(), physics.to_string());
        assert!(
            e.render(flags)
                .starts_with("invalid --roughness '2': expected a number")
        );
    }

    #[test]
    fn every_quantity_is_named_as_its_field_is() {
        for quantity in [
            Quantity::Anisotropy,
            Quantity::BlenderVersion,
            Quantity::Distribution,
            Quantity::Engine,
            Quantity::Model,
            Quantity::ModelParameter("Phong exponent n"),
            Quantity::Roughness,
            Quantity::ViewCosine,
        ] {
            assert_eq!(quantity.name(), Field::from(quantity).name());
        }
    }

    #[test]
    fn a_blender_error_keeps_its_log_and_command_after_the_message() {
        let e = Error::Blender {
            message: Hint::new("timed out ({})", [Field::Timeout]),
            log: Some(PathBuf::from("/tmp/x.log")),
            command: Some("blender -b".into()),
        };
        assert_eq!(
            e.render(flags),
            "timed out (--timeout); log: /tmp/x.log; command: blender -b"
        );
    }
}
