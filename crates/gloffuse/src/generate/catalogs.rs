//! Asset catalogs: where the groups show up in Blender's Asset Browser and, from 4.0, in
//! the shader editor's Add menu. Shader groups (a BSDF output) go in the catalog `Shader`,
//! next to Glossy BSDF; the helper groups in `Shader/Gloffuse Helpers`. Catalog ids are
//! UUIDv5 of the path, so every run gives the same ones.
//!
//! `blender_assets.cats.txt` (Blender's catalog definition file: a `VERSION 1` line, then
//! `UUID:path:simple name` lines) is merged, never clobbered: the user's lines stay as
//! they are, a catalog the user already has for one of our paths is used as it is, and only
//! the missing ones are added.

use serde::Serialize;
use uuid::Uuid;

/// The name of Blender's catalog definition file, beside the .blend (the library root).
pub const FILE_NAME: &str = "blender_assets.cats.txt";

/// One catalog: its id, its path, and the "simple name" Blender stores with it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Catalog {
    pub uuid: String,
    pub path: String,
    pub simple_name: String,
}

impl Catalog {
    /// The catalog at `path`, with the id gloffuse gives it.
    pub fn at(path: &str) -> Self {
        let namespace = Uuid::new_v5(&Uuid::NAMESPACE_URL, b"gloffuse:asset-catalog");
        Catalog {
            uuid: Uuid::new_v5(&namespace, path.as_bytes()).to_string(),
            path: path.to_string(),
            simple_name: path.replace('/', "-"),
        }
    }

    /// Its line in a definition file.
    fn line(&self) -> String {
        format!("{}:{}:{}\n", self.uuid, self.path, self.simple_name)
    }
}

/// The catalogs of the two kinds of group.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Catalogs {
    /// Groups with a BSDF output.
    pub shader: Catalog,
    /// Groups the shader groups use (gains, the shading normal).
    pub helper: Catalog,
}

impl Default for Catalogs {
    fn default() -> Self {
        Catalogs {
            shader: Catalog::at("Shader"),
            helper: Catalog::at("Shader/Gloffuse Helpers"),
        }
    }
}

/// A catalog line of a definition file: `(uuid, path)`.
fn parse_line(line: &str) -> Option<(&str, &str)> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') || line.starts_with("VERSION") {
        return None;
    }
    let mut parts = line.splitn(3, ':');
    Some((parts.next()?, parts.next()?))
}

impl Catalogs {
    /// Merges these catalogs into the definition file `existing` (if there is one): returns
    /// the catalogs to assign (the user's own id where they already have one of our paths)
    /// and the file's new text.
    pub fn merge(&self, existing: Option<&str>) -> (Catalogs, String) {
        let lines: Vec<(&str, &str)> = existing
            .map(|text| text.lines().filter_map(parse_line).collect())
            .unwrap_or_default();
        let mut text = match existing {
            Some(t) if !t.trim().is_empty() => {
                let mut t = t.to_string();
                if !t.ends_with('\n') {
                    t.push('\n');
                }
                t
            }
            _ => HEADER.to_string(),
        };
        let mut resolve = |ours: &Catalog| match lines.iter().find(|(_, path)| *path == ours.path) {
            Some((uuid, _)) => Catalog {
                uuid: uuid.to_string(),
                ..ours.clone()
            },
            None => {
                text.push_str(&format!(
                    "{}:{}:{}\n",
                    ours.uuid, ours.path, ours.simple_name
                ));
                ours.clone()
            }
        };
        let shader = resolve(&self.shader);
        let helper = resolve(&self.helper);
        (Catalogs { shader, helper }, text)
    }

    /// A definition file of these catalogs alone (the one an extension bundles).
    pub fn definition_file(&self) -> String {
        let mut text = HEADER.to_string();
        for c in [&self.shader, &self.helper] {
            text.push_str(&c.line());
        }
        text
    }
}

/// The opening of a new definition file, as Blender writes it.
const HEADER: &str = "# This is an Asset Catalog Definition file for Blender.\n#\n\
    # Empty lines and lines starting with `#` will be ignored.\n\
    # The first non-ignored line should be the version indicator.\n\
    # Other lines are of the format \"UUID:catalog/path/for/assets:simple catalog name\"\n\n\
    VERSION 1\n\n";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_uuid_v5_and_stable() {
        let a = Catalog::at("Shader");
        assert_eq!(a, Catalog::at("Shader"));
        let id = Uuid::parse_str(&a.uuid).unwrap();
        assert_eq!(id.get_version_num(), 5);
        assert_ne!(a.uuid, Catalog::at("Shader/Gloffuse Helpers").uuid);
    }

    #[test]
    fn merging_keeps_the_users_catalogs() {
        let ours = Catalogs::default();
        let (fresh, text) = ours.merge(None);
        assert_eq!(fresh, ours);
        assert_eq!(text, ours.definition_file());
        assert!(text.contains("\nVERSION 1\n"));
        assert!(text.contains(&format!("{}:Shader:Shader\n", ours.shader.uuid)));
        // Merging again adds nothing.
        assert_eq!(ours.merge(Some(&text)).1, text);
        // A user's file: their lines stay, their "Shader" catalog is used.
        let user = "VERSION 1\n\n# mine\n0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01:Shader:My shaders\n\
                    1b2c3d4e-0000-4000-8000-000000000001:Props/Chairs:Props-Chairs";
        let (merged, text) = ours.merge(Some(user));
        assert!(text.starts_with(user));
        assert_eq!(merged.shader.uuid, "0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01");
        assert_eq!(merged.helper, ours.helper);
        assert_eq!(text.matches(":Shader:").count(), 1);
        assert!(text.ends_with(&format!(
            "{}:Shader/Gloffuse Helpers:Shader-Gloffuse Helpers\n",
            ours.helper.uuid
        )));
    }
}
