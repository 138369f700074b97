//! Tests only: the Rust side of the Rust↔Python contract. `blender/gloffuse_blender/contract.py`
//! defines the fields of every parameter document and result line once (its `CONTRACT`, a
//! Python literal kept valid JSON); the jobs refuse a document or a result with a field it
//! does not list, or without one it requires. These tests serialise the documents the
//! library really builds and check that they carry exactly those fields (every field they
//! send is listed, every required one is there, every listed one is sent by some document),
//! and that the typed result structs read no field the contract lacks.

use std::collections::{BTreeMap, BTreeSet};

use serde::Deserialize;
use serde_json::{Map, Value};

use crate::generate::bundle::MODULES;

/// contract.py's `CONTRACT`, read as JSON.
fn contract() -> Value {
    let text = MODULES
        .iter()
        .find(|(name, _)| *name == "contract")
        .expect("contract.py is bundled")
        .1;
    let (_, literal) = text
        .split_once("CONTRACT = ")
        .expect("contract.py defines CONTRACT");
    serde_json::Deserializer::from_str(literal)
        .into_iter::<Value>()
        .next()
        .expect("CONTRACT has a value")
        .expect("CONTRACT is JSON")
}

/// A field's object kind: `""` for a plain value, `KIND` or `KIND[]`.
type Fields = BTreeMap<String, String>;

/// Checks values against the contract, remembering which fields of each kind were sent.
pub(crate) struct Checker {
    contract: Value,
    sent: BTreeMap<String, BTreeSet<String>>,
}

impl Checker {
    pub(crate) fn new() -> Self {
        Checker {
            contract: contract(),
            sent: BTreeMap::new(),
        }
    }

    /// The `required` or `optional` fields of `kind`, without its flattened kinds.
    fn own(&self, kind: &str, which: &str) -> Fields {
        let spec = self.contract.get(kind);
        let spec = spec.unwrap_or_else(|| panic!("the contract has no kind {kind}"));
        let fields = spec.get(which).and_then(Value::as_object);
        fields
            .into_iter()
            .flatten()
            .map(|(k, v)| (k.clone(), v.as_str().unwrap_or_default().to_string()))
            .collect()
    }

    /// Every field `kind` may hold (its own and its flattened kinds'), each with the kind
    /// that lists it.
    pub(crate) fn all_fields(&self, kind: &str) -> BTreeMap<String, String> {
        let mut all = BTreeMap::new();
        for flat in self.flattened(kind).keys() {
            for which in ["required", "optional"] {
                all.extend(self.own(flat, which).into_keys().map(|k| (k, flat.clone())));
            }
        }
        for which in ["required", "optional"] {
            all.extend(
                self.own(kind, which)
                    .into_keys()
                    .map(|k| (k, kind.to_string())),
            );
        }
        all
    }

    fn flattened(&self, kind: &str) -> BTreeMap<String, bool> {
        let flatten = self.contract[kind]
            .get("flatten")
            .and_then(Value::as_object);
        flatten
            .into_iter()
            .flatten()
            .map(|(k, v)| (k.clone(), v == "required"))
            .collect()
    }

    /// `value` holds exactly the fields `kind` allows, and every object in it those of its
    /// own kind; records what was sent.
    pub(crate) fn check(&mut self, value: &Value, kind: &str, at: &str) -> Result<(), String> {
        let object = value
            .as_object()
            .ok_or_else(|| format!("{at} is not an object"))?;
        let mut parts = vec![(kind.to_string(), true)];
        for (flat, required) in self.flattened(kind) {
            let present = self
                .own(&flat, "required")
                .keys()
                .any(|k| object.contains_key(k));
            if required || present {
                parts.push((flat, true));
            }
        }
        let mut allowed = BTreeMap::new();
        for (part, _) in &parts {
            for (which, required) in [("required", true), ("optional", false)] {
                for (field, inner) in self.own(part, which) {
                    allowed.insert(field, (part.clone(), inner, required));
                }
            }
        }
        for (field, (part, _, required)) in &allowed {
            if *required && !object.contains_key(field) {
                return Err(format!("{at}: the {part} field {field} is missing"));
            }
        }
        for (field, item) in object {
            let Some((part, inner, _)) = allowed.get(field) else {
                return Err(format!("{at}: {field} is not a field of {kind}"));
            };
            self.sent
                .entry(part.clone())
                .or_default()
                .insert(field.clone());
            self.check_inner(item, inner, &format!("{at}.{field}"))?;
        }
        Ok(())
    }

    fn check_inner(&mut self, item: &Value, inner: &str, at: &str) -> Result<(), String> {
        match (inner, item) {
            ("", _) | (_, Value::Null) => Ok(()),
            (_, Value::Array(items)) if inner.ends_with("[]") => {
                let kind = &inner[..inner.len() - 2];
                for (i, element) in items.iter().enumerate() {
                    self.check(element, kind, &format!("{at}[{i}]"))?;
                }
                Ok(())
            }
            _ if inner.ends_with("[]") => Err(format!("{at} is not a list")),
            _ => self.check(item, inner, at),
        }
    }

    /// The fields of `kinds` (and of every kind inside them) that no checked value sent.
    pub(crate) fn unsent(&self, kinds: &[&str]) -> Vec<String> {
        let mut todo: Vec<String> = kinds.iter().map(|k| k.to_string()).collect();
        let mut done = BTreeSet::new();
        let mut unsent = Vec::new();
        while let Some(kind) = todo.pop() {
            if !done.insert(kind.clone()) {
                continue;
            }
            todo.extend(self.flattened(&kind).into_keys());
            let sent = self.sent.get(&kind).cloned().unwrap_or_default();
            for which in ["required", "optional"] {
                for (field, inner) in self.own(&kind, which) {
                    if !sent.contains(&field) {
                        unsent.push(format!("{kind}.{field}"));
                    }
                    if !inner.is_empty() {
                        todo.push(inner.trim_end_matches("[]").to_string());
                    }
                }
            }
        }
        unsent.sort();
        unsent
    }
}

/// Which fields a `#[derive(Deserialize)]` struct reads: serde hands them to
/// `deserialize_struct`, where this deserializer keeps them and stops.
pub(crate) fn struct_fields<T: for<'de> Deserialize<'de>>() -> &'static [&'static str] {
    use serde::de::{Error as _, Visitor, value::Error};
    struct Introspect<'a>(&'a mut &'static [&'static str]);
    impl<'de> serde::Deserializer<'de> for Introspect<'_> {
        type Error = Error;
        fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Error> {
            Err(Error::custom("not a struct"))
        }
        fn deserialize_struct<V: Visitor<'de>>(
            self,
            _: &'static str,
            fields: &'static [&'static str],
            _: V,
        ) -> Result<V::Value, Error> {
            *self.0 = fields;
            Err(Error::custom("fields read"))
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes
            byte_buf option unit unit_struct newtype_struct seq tuple tuple_struct map enum
            identifier ignored_any
        }
    }
    let mut fields: &'static [&'static str] = &[];
    let _ = T::deserialize(Introspect(&mut fields));
    assert!(
        !fields.is_empty(),
        "{} is not a plain struct",
        std::any::type_name::<T>()
    );
    fields
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::audit::job::{
        FixItem, JobFinding, JobFixed, JobMaterial, JobResult, JobWaiver, document,
    };
    use crate::bench::audit::library_document;
    use crate::fit::Coefficients;
    use crate::generate::{ColorModel, Curves, GenerateParams, Mode};
    use crate::measure::{BlenderVersion, Distribution, Engine, Masking, Roughness};
    use crate::verify::{Plan, RenderSettings};

    fn seed() -> GenerateParams {
        let seed = Coefficients::load("seed").unwrap();
        let curves = Curves::Pinned {
            coefficients: &seed,
            name: "seed",
        };
        GenerateParams::new(curves, &Masking::ALL, &[Mode::Roughness], ColorModel::Exact).unwrap()
    }

    fn to_value(value: impl serde::Serialize) -> Value {
        serde_json::to_value(value).unwrap()
    }

    #[test]
    fn the_contract_is_read_whole() {
        let checker = Checker::new();
        let kinds = checker.contract.as_object().unwrap();
        assert!(kinds.len() > 20, "{:?}", kinds.keys());
        let wrong = Value::Object(Map::from_iter([("nothing".into(), Value::Null)]));
        let err = Checker::new().check(&wrong, "catalog", "c").unwrap_err();
        assert_eq!(err, "c: the catalog field path is missing");
    }

    /// Every document the library sends, checked; together they send every field the
    /// contract lists for a document.
    #[test]
    fn the_documents_carry_exactly_the_contracts_fields() {
        let mut checker = Checker::new();
        let presets = |engine, modes: &[Mode]| {
            GenerateParams::new(
                Curves::Presets(&[engine]),
                &Masking::ALL,
                modes,
                ColorModel::Physical,
            )
            .unwrap()
        };
        let generate = [
            seed(),
            presets(Engine::Cycles, &Mode::ALL),
            presets(Engine::Eevee, &[Mode::Roughness, Mode::View]),
        ];
        for (i, params) in generate.iter().enumerate() {
            let at = format!("generate document {i}");
            checker
                .check(&to_value(params), "generate_document", &at)
                .unwrap();
        }
        let render = RenderSettings::for_engine(Engine::Cycles);
        let plan = Plan::verify(
            &[Distribution::Ggx],
            &[Roughness::new(0.5).unwrap()],
            &[],
            render,
        );
        let furnace = plan.params(&generate[0], Mode::Roughness, [1.0; 3], Path::new("f.exr"));
        checker
            .check(&to_value(furnace), "furnace_document", "furnace document")
            .unwrap();
        let fix = [FixItem {
            material: 0,
            scale: Some(0.5),
        }];
        let exr = Path::new("audit.exr");
        let oldest = BlenderVersion::OLDEST;
        let newest = BlenderVersion::NEWEST_KNOWN;
        let cases = [
            (oldest, None, None),
            (newest, Some(&generate[0]), Some(render)),
        ];
        for (version, groups, render) in cases {
            let audit = document(version, groups, render, exr, exr, &fix);
            checker
                .check(&to_value(audit), "audit_document", "audit document")
                .unwrap();
        }
        let bench = library_document(Path::new("bench.blend"), 0, 4);
        checker
            .check(&bench, "bench_library_document", "bench document")
            .unwrap();
        let kinds = [
            "generate_document",
            "furnace_document",
            "audit_document",
            "bench_library_document",
        ];
        assert_eq!(checker.unsent(&kinds), Vec::<String>::new());
    }

    #[test]
    fn an_unknown_or_missing_field_is_found() {
        let mut params = to_value(seed());
        params["groups"][0]["families"][1]["extra"] = Value::Bool(true);
        let err = Checker::new()
            .check(&params, "generate_document", "d")
            .unwrap_err();
        assert_eq!(
            err,
            "d.groups[0].families[1]: extra is not a field of family"
        );
        let mut params = to_value(seed());
        params["catalogs"]["helper"]
            .as_object_mut()
            .unwrap()
            .remove("uuid");
        let err = Checker::new()
            .check(&params, "generate_document", "d")
            .unwrap_err();
        assert_eq!(err, "d.catalogs.helper: the catalog field uuid is missing");
    }

    /// The typed result lines read only fields the contract gives them (the untyped ones,
    /// generate's and the furnace's, are read by key in `generate/mod.rs` and
    /// `verify/render.rs`).
    #[test]
    fn the_result_types_read_only_the_contracts_fields() {
        let checker = Checker::new();
        for (kind, fields) in [
            ("audit_result", struct_fields::<JobResult>()),
            ("audit_material", struct_fields::<JobMaterial>()),
            ("audit_finding", struct_fields::<JobFinding>()),
            ("audit_waiver", struct_fields::<JobWaiver>()),
            ("audit_fixed", struct_fields::<JobFixed>()),
        ] {
            let listed = checker.all_fields(kind);
            for field in fields {
                assert!(listed.contains_key(*field), "{kind} lacks {field}");
            }
        }
    }
}
