//! The Blender extension (4.2+): a .zip Blender installs from disk, holding
//! `blender_manifest.toml`, a small add-on (GPL-3.0-or-later) that registers the bundled
//! library as an asset library when enabled and removes it when disabled, and the library
//! itself (the .blend of CC0 node groups and its catalog file). The add-on also holds the
//! audit's panel and operators (issue 42), which read the rule catalogue and the
//! integrator's predictions from the file an [`AuditCatalogue`] writes: the audit is a later
//! stage than generate, so its caller (the CLI) hands it in
//! (`gloffuse::audit::catalogue::EXTENSION`).

use std::fmt;
use std::io::{Cursor, Write};

use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, DateTime, ZipWriter};

use crate::blender::Need;
use crate::error::{Error, Field, Hint};
use crate::measure::BlenderVersion;

/// The first Blender with extensions.
pub const FIRST_BLENDER: BlenderVersion = BlenderVersion { major: 4, minor: 2 };

/// The extension's id: its Python package is `bl_ext.<repository>.gloffuse`.
pub const ID: &str = "gloffuse";

/// Where the library sits inside the extension (the add-on reads it from there).
pub const LIBRARY_FOLDER: &str = "library";
pub const LIBRARY_FILE: &str = "gloffuse.blend";

const LICENSE: &str = include_str!("../../../../LICENSE");

/// Writes the audit's data for the extension's panel, for the Blender that builds it.
#[derive(Clone, Copy)]
pub struct AuditCatalogue {
    /// Its name inside the extension.
    pub file_name: &'static str,
    pub write: fn(BlenderVersion) -> String,
}

impl fmt::Debug for AuditCatalogue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "AuditCatalogue({})", self.file_name)
    }
}

impl PartialEq for AuditCatalogue {
    fn eq(&self, other: &Self) -> bool {
        self.file_name == other.file_name && std::ptr::fn_addr_eq(self.write, other.write)
    }
}

/// The manifest. `blender_version_min` is the Blender that saved the library: an older one
/// may not read the file (5.0's .blend format is new) or its node sockets.
pub fn manifest(built_with: BlenderVersion) -> String {
    format!(
        r#"schema_version = "1.0.0"

id = "{ID}"
version = "{version}"
name = "Gloffuse"
tagline = "Glossy node groups that keep their brightness at any roughness"
maintainer = "The gloffuse authors"
type = "add-on"
tags = ["Material", "Node"]

blender_version_min = "{major}.{minor}.0"

# The add-on's code; the node groups it bundles are CC0-1.0 (see each asset's licence).
license = ["SPDX:GPL-3.0-or-later"]
copyright = ["2026 The gloffuse authors"]
"#,
        version = env!("CARGO_PKG_VERSION"),
        major = built_with.major,
        minor = built_with.minor,
    )
}

/// What building an extension needs of the Blender that builds it: no extension system
/// before 4.2, and the library it packs is saved by that Blender.
pub const NEED: Need = Need {
    version: FIRST_BLENDER,
    by: Field::Extension,
    why: "extensions came with 4.2, and the library it packs is saved by the Blender that \
          builds it",
};

/// Refuses a Blender before 4.2 (see [`NEED`]).
pub fn can_build(built_with: BlenderVersion) -> Result<(), Error> {
    if built_with < NEED.version {
        return Err(Error::input(
            Field::Blender,
            format!("Blender {}.{}", built_with.major, built_with.minor),
            Hint::new(
                format!("Blender 4.2 or later for {{}} ({})", NEED.why),
                [NEED.by],
            ),
        ));
    }
    Ok(())
}

/// How Blender installs the .zip: as an extension (4.2 and later: a manifest beside the
/// add-on) or as a classic add-on (3.4 to 4.1, and 4.2 and later as a legacy add-on: one
/// folder, named [`ID`], whose `__init__.py` opens with `bl_info`). The add-on is the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Packaging {
    Extension,
    Addon,
}

/// The classic add-on's `bl_info`, which Blender reads without running the add-on.
/// `blender` is the Blender that saved the library: an older one may not read the file.
pub fn bl_info(built_with: BlenderVersion) -> String {
    let version: Vec<&str> = env!("CARGO_PKG_VERSION").split('.').collect();
    format!(
        r#"# SPDX-License-Identifier: GPL-3.0-or-later
bl_info = {{
    "name": "Gloffuse",
    "author": "The gloffuse authors",
    "version": ({}),
    "blender": ({}, {}, 0),
    "location": "Properties > Material > Gloffuse, Shader Editor > Sidebar > Gloffuse",
    "description": "Glossy node groups that keep their brightness at any roughness",
    "category": "Material",
}}
"#,
        version.join(", "),
        built_with.major,
        built_with.minor,
    )
}

/// The .zip, from the library .blend and its catalog file, built by Blender `built_with`
/// (4.2 or later for an extension), with the audit's data when `audit` is given (without
/// it the panel says it has none). Entries are stored with a fixed date, so the same
/// inputs give the same bytes.
pub fn package(
    packaging: Packaging,
    blend: &[u8],
    catalogs: &str,
    built_with: BlenderVersion,
    audit: Option<AuditCatalogue>,
) -> Result<Vec<u8>, Error> {
    let (folder, first, init) = match packaging {
        Packaging::Extension => {
            can_build(built_with)?;
            (String::new(), Some(manifest(built_with)), String::new())
        }
        Packaging::Addon => (format!("{ID}/"), None, bl_info(built_with)),
    };
    let init = init + &super::bundle::addon();
    let audit = audit.map(|a| (a.file_name.to_string(), (a.write)(built_with)));
    let mut files: Vec<(String, &[u8])> = Vec::new();
    if let Some(manifest) = &first {
        files.push(("blender_manifest.toml".into(), manifest.as_bytes()));
    }
    files.extend([
        ("__init__.py".into(), init.as_bytes()),
        ("LICENSE".into(), LICENSE.as_bytes()),
        (format!("{LIBRARY_FOLDER}/{LIBRARY_FILE}"), blend),
        (
            format!("{LIBRARY_FOLDER}/{}", super::catalogs::FILE_NAME),
            catalogs.as_bytes(),
        ),
    ]);
    if let Some((name, text)) = &audit {
        files.push((name.clone(), text.as_bytes()));
    }
    let mut zip = ZipWriter::new(Cursor::new(Vec::new()));
    let options = SimpleFileOptions::default()
        .compression_method(CompressionMethod::Deflated)
        .last_modified_time(DateTime::default())
        .unix_permissions(0o644);
    let failed = |e: &dyn std::fmt::Display| Error::Write {
        path: "(the add-on archive, in memory)".into(),
        message: e.to_string(),
    };
    for (name, bytes) in files {
        zip.start_file(format!("{folder}{name}"), options)
            .map_err(|e| failed(&e))?;
        zip.write_all(bytes).map_err(|e| failed(&e))?;
    }
    Ok(zip.finish().map_err(|e| failed(&e))?.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    /// The archive and its entries' names, sorted.
    fn open(bytes: Vec<u8>) -> (zip::ZipArchive<Cursor<Vec<u8>>>, Vec<String>) {
        let archive = zip::ZipArchive::new(Cursor::new(bytes)).unwrap();
        let mut names: Vec<String> = archive
            .file_names()
            .map(|n| n.unwrap().into_owned())
            .collect();
        names.sort();
        (archive, names)
    }

    #[test]
    fn the_archive_holds_the_manifest_addon_and_library() {
        let v45 = BlenderVersion { major: 4, minor: 5 };
        let audit = AuditCatalogue {
            file_name: "audit.json",
            write: |v| format!("{{\"blender\": [{}, {}]}}", v.major, v.minor),
        };
        let bytes = package(
            Packaging::Extension,
            b"BLENDER-fake",
            "VERSION 1\n",
            v45,
            Some(audit),
        )
        .unwrap();
        assert_eq!(
            bytes,
            package(
                Packaging::Extension,
                b"BLENDER-fake",
                "VERSION 1\n",
                v45,
                Some(audit)
            )
            .unwrap()
        );
        let (mut archive, names) = open(bytes);
        assert_eq!(
            names,
            [
                "LICENSE",
                "__init__.py",
                "audit.json",
                "blender_manifest.toml",
                "library/blender_assets.cats.txt",
                "library/gloffuse.blend"
            ]
        );
        let mut manifest = String::new();
        archive
            .by_name("blender_manifest.toml")
            .unwrap()
            .read_to_string(&mut manifest)
            .unwrap();
        assert!(manifest.contains("\nblender_version_min = \"4.5.0\"\n"));
        let mut blend = Vec::new();
        archive
            .by_name("library/gloffuse.blend")
            .unwrap()
            .read_to_end(&mut blend)
            .unwrap();
        assert_eq!(blend, b"BLENDER-fake");
        let mut audit = String::new();
        archive
            .by_name("audit.json")
            .unwrap()
            .read_to_string(&mut audit)
            .unwrap();
        assert_eq!(audit, "{\"blender\": [4, 5]}");
    }

    #[test]
    fn blender_before_4_2_cannot_build_one() {
        let v34 = BlenderVersion { major: 3, minor: 4 };
        let err = package(Packaging::Extension, b"", "", v34, None).unwrap_err();
        assert!(err.to_string().contains("4.2 or later"), "{err}");
    }

    #[test]
    fn the_addon_is_one_folder_whose_init_opens_with_bl_info() {
        let v34 = BlenderVersion { major: 3, minor: 4 };
        let bytes = package(Packaging::Addon, b"BLENDER-fake", "VERSION 1\n", v34, None).unwrap();
        let (mut archive, names) = open(bytes);
        assert_eq!(
            names,
            [
                "gloffuse/LICENSE",
                "gloffuse/__init__.py",
                "gloffuse/library/blender_assets.cats.txt",
                "gloffuse/library/gloffuse.blend"
            ]
        );
        let mut init = String::new();
        archive
            .by_name("gloffuse/__init__.py")
            .unwrap()
            .read_to_string(&mut init)
            .unwrap();
        let lines: Vec<&str> = init.lines().take(6).collect();
        assert_eq!(lines[1], "bl_info = {", "{init:.300}");
        assert_eq!(lines[5], "    \"blender\": (3, 4, 0),");
        let version = env!("CARGO_PKG_VERSION").replace('.', ", ");
        assert_eq!(lines[4], format!("    \"version\": ({version}),"));
        assert!(init.contains("def register():"));
    }
}
