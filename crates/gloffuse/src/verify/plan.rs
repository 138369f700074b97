//! What one Blender process renders: a grid of furnace spheres, one per cell, row-major with
//! row 0 at the top. Each distribution gets an uncorrected row and a corrected row; a final
//! row holds Blender's own energy-conserving answer as the reference. In layered mode the
//! rows repeat for every index of refraction, "uncorrected" is the Mix Shader artists build
//! by hand and the reference is Principled BSDF; in anisotropic mode they repeat for every
//! anisotropy, each sphere's tangent the constant world X; in glass mode they repeat for
//! every index of refraction, the spheres are solid Glass BSDFs and the reference is
//! Multiscatter GGX glass. In EEVEE a last cell holds a white Diffuse sphere: how bright
//! EEVEE's lighting itself is.

use serde::Serialize;
use std::path::Path;

use crate::generate::{GenerateParams, GroupSpec, Mode};
use crate::measure::{Distribution, Engine, Roughness};

use super::modes::spec;

/// What a sphere is shaded with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind", content = "distribution")]
pub enum Role {
    /// The plain Glossy BSDF of that distribution (layered mode: Mix Shader with a Fresnel
    /// factor over Diffuse and that Glossy).
    Uncorrected(Distribution),
    /// The mode's gloffuse shader group of that distribution.
    Corrected(Distribution),
    /// Blender's own energy-conserving answer: Glossy with `MULTI_GGX` (layered mode:
    /// Principled BSDF).
    Reference,
    /// A white Diffuse BSDF: the engine's lighting (EEVEE Next's world probe loses 0.8 %).
    Lighting,
}

impl Role {
    /// How a report names the spheres of this role in `mode` (`GGX Mix Shader`).
    pub fn label(self, mode: Mode) -> String {
        let spec = spec(mode);
        match self {
            Role::Uncorrected(d) => format!("{} {}", d.label(), spec.uncorrected),
            Role::Corrected(d) => format!("{} {}", d.label(), spec.corrected),
            Role::Reference => spec.reference.to_string(),
            Role::Lighting => "Diffuse BSDF".to_string(),
        }
    }
}

/// What a block of verify rows holds fixed besides distribution and roughness: the coat's
/// index of refraction (layered mode) or the lobe's anisotropy (anisotropic mode). A report
/// shows it as its own field (`"ior": 1.5`, `"anisotropy": 0.9`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Block {
    Ior(f64),
    Anisotropy(f64),
}

impl Block {
    pub fn ior(self) -> Option<f64> {
        match self {
            Block::Ior(n) => Some(n),
            Block::Anisotropy(_) => None,
        }
    }

    pub fn anisotropy(self) -> Option<f64> {
        match self {
            Block::Anisotropy(a) => Some(a),
            Block::Ior(_) => None,
        }
    }

    /// `IOR 1.5`, `anisotropy 0.9`.
    pub fn label(self) -> String {
        match self {
            Block::Ior(n) => format!("IOR {n}"),
            Block::Anisotropy(a) => format!("anisotropy {a}"),
        }
    }
}

/// Every block of rows: each of `blocks`, or one plain block when there are none.
pub fn block_slots(blocks: &[Block]) -> Vec<Option<Block>> {
    if blocks.is_empty() {
        vec![None]
    } else {
        blocks.iter().copied().map(Some).collect()
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    pub role: Role,
    pub roughness: Roughness,
    /// The coat's index or the lobe's anisotropy (layered and anisotropic mode only).
    pub block: Option<Block>,
}

/// One row of the verdict: a distribution at one roughness (and, in layered and
/// anisotropic mode, one block's index or anisotropy), and the cells of its uncorrected and corrected spheres. Its `id`
/// is its place in [`Plan::rows`]; the verdict's row carries it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanRow {
    pub id: usize,
    pub distribution: Distribution,
    pub roughness: Roughness,
    pub block: Option<Block>,
    pub uncorrected: usize,
    pub corrected: usize,
}

/// A reference sphere of the sweep (Multiscatter GGX, at the block's anisotropy, or
/// Principled BSDF at the block's index).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanReference {
    pub roughness: Roughness,
    pub block: Option<Block>,
    pub cell: usize,
}

/// Render settings with their reasons.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub engine: Engine,
    /// Pixels per sphere cell.
    pub cell: u32,
    pub samples: u32,
    pub seed: u32,
    /// Sphere diameter as a fraction of the cell, leaving a margin so the pixel filter
    /// never bleeds into a neighbour.
    pub radius_fraction: f64,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings::for_engine(Engine::Cycles)
    }
}

impl RenderSettings {
    /// The verify defaults of an engine.
    pub fn for_engine(engine: Engine) -> Self {
        RenderSettings {
            engine,
            cell: 64,
            samples: spec(Mode::Roughness).defaults(engine).samples,
            seed: 0,
            radius_fraction: 0.9,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Plan {
    pub cells: Vec<Cell>,
    pub columns: usize,
    pub settings: RenderSettings,
    /// The rows a verify sweep judges, in the verdict's order (none in other plans).
    pub rows: Vec<PlanRow>,
    /// The reference spheres of a verify sweep, per index then roughness.
    pub references: Vec<PlanReference>,
}

impl Plan {
    /// The verify sweep: for each distribution (in `groups` order) an uncorrected row and a
    /// corrected row over `roughness`, then the reference row; all of it once per block in
    /// `blocks` (layered and anisotropic mode), or once when `blocks` is empty.
    pub fn verify(
        distributions: &[Distribution],
        roughness: &[Roughness],
        blocks: &[Block],
        settings: RenderSettings,
    ) -> Self {
        let columns = roughness.len();
        // Each block of image rows: two per distribution, then the reference.
        let block_rows = 2 * distributions.len() + 1;
        let mut plan = Plan::of(Vec::new(), columns, settings);
        for (b, block) in block_slots(blocks).into_iter().enumerate() {
            let roles = distributions
                .iter()
                .flat_map(|&d| [Role::Uncorrected(d), Role::Corrected(d)])
                .chain([Role::Reference]);
            for role in roles {
                plan.cells.extend(roughness.iter().map(|&r| Cell {
                    role,
                    roughness: r,
                    block,
                }));
            }
            let cell = |line: usize, column: usize| (b * block_rows + line) * columns + column;
            for (k, &d) in distributions.iter().enumerate() {
                for (c, &r) in roughness.iter().enumerate() {
                    plan.rows.push(PlanRow {
                        id: plan.rows.len(),
                        distribution: d,
                        roughness: r,
                        block,
                        uncorrected: cell(2 * k, c),
                        corrected: cell(2 * k + 1, c),
                    });
                }
            }
            plan.references
                .extend(roughness.iter().enumerate().map(|(c, &r)| PlanReference {
                    roughness: r,
                    block,
                    cell: cell(block_rows - 1, c),
                }));
        }
        plan.with_lighting()
    }

    /// A plan of `cells` alone, `columns` to a row, with no rows to judge.
    pub fn of(cells: Vec<Cell>, columns: usize, settings: RenderSettings) -> Self {
        Plan {
            cells,
            columns,
            settings,
            rows: Vec::new(),
            references: Vec::new(),
        }
    }

    /// EEVEE's plans end with a white Diffuse sphere, which says how bright its lighting is.
    fn with_lighting(mut self) -> Self {
        if self.settings.engine == Engine::Eevee {
            self.cells.push(Cell {
                role: Role::Lighting,
                roughness: Roughness::new(0.0).expect("0 is a roughness"),
                block: None,
            });
        }
        self
    }

    /// The white Diffuse sphere's cell (EEVEE only).
    pub fn lighting(&self) -> Option<usize> {
        self.cells.iter().position(|c| c.role == Role::Lighting)
    }

    /// Uncorrected spheres only (what `refresh` measures).
    pub fn measure(
        distributions: &[Distribution],
        roughness: &[Roughness],
        settings: RenderSettings,
    ) -> Self {
        let cells = distributions
            .iter()
            .flat_map(|&d| {
                roughness.iter().map(move |&r| Cell {
                    role: Role::Uncorrected(d),
                    roughness: r,
                    block: None,
                })
            })
            .collect();
        Plan::of(cells, roughness.len(), settings).with_lighting()
    }

    /// How many lines of cells the image has.
    pub fn image_rows(&self) -> usize {
        self.cells.len().div_ceil(self.columns)
    }

    /// The parameter document for `furnace_main.py` (the groups plus the furnace section).
    /// Corrected spheres use the shader group of `mode`; every sphere is of colour `color`.
    pub fn params(
        &self,
        groups: &GenerateParams,
        mode: Mode,
        color: [f64; 3],
        output: &Path,
    ) -> FurnaceParams {
        let shader_of = |d: Distribution| -> String {
            groups
                .groups
                .iter()
                .find(|g| g.distribution == d)
                .and_then(|g: &GroupSpec| g.shader_for(mode))
                .expect("a corrected row only exists for distributions with a group of its mode")
                .to_string()
        };
        let spheres = self
            .cells
            .iter()
            .map(|c| sphere_spec(c, mode, &shader_of))
            .collect();
        FurnaceParams {
            generate: groups.clone(),
            furnace: FurnaceSection {
                engine: self.settings.engine,
                solid: spec(mode).solid,
                cell: self.settings.cell,
                columns: self.columns,
                samples: self.settings.samples,
                seed: self.settings.seed,
                radius_fraction: self.settings.radius_fraction,
                color,
                output: output.to_string_lossy().into_owned(),
                threads: 0,
                spheres,
            },
        }
    }
}

/// What a cell's sphere is shaded with in `mode`; `group` names a distribution's group.
fn sphere_spec(c: &Cell, mode: Mode, group: &dyn Fn(Distribution) -> String) -> SphereSpec {
    // A solid sphere's plain and reference cells are Glass BSDFs.
    let glass = spec(mode).solid;
    let anisotropy = c.block.and_then(Block::anisotropy);
    match (c.role, c.block.and_then(Block::ior)) {
        (Role::Uncorrected(d), Some(ior)) if glass => SphereSpec::Glass {
            distribution: d.blender_enum(),
            roughness: c.roughness,
            ior,
        },
        (Role::Reference, Some(ior)) if glass => SphereSpec::Glass {
            distribution: "MULTI_GGX",
            roughness: c.roughness,
            ior,
        },
        (Role::Uncorrected(d), Some(ior)) => SphereSpec::Mix {
            distribution: d.blender_enum(),
            roughness: c.roughness,
            ior,
        },
        (Role::Uncorrected(d), None) => SphereSpec::Plain {
            distribution: d.blender_enum(),
            roughness: c.roughness,
            anisotropy,
        },
        (Role::Reference, Some(ior)) => SphereSpec::Principled {
            roughness: c.roughness,
            ior,
        },
        (Role::Reference, None) => SphereSpec::Plain {
            distribution: "MULTI_GGX",
            roughness: c.roughness,
            anisotropy,
        },
        (Role::Lighting, _) => SphereSpec::Diffuse {
            roughness: c.roughness,
        },
        (Role::Corrected(d), ior) => SphereSpec::Group {
            group: group(d),
            roughness: c.roughness,
            ior,
            anisotropy,
        },
    }
}

#[derive(Clone, Debug, Serialize)]
#[serde(tag = "shader", rename_all = "kebab-case")]
pub enum SphereSpec {
    /// A Glossy BSDF (with an anisotropy: Blender's anisotropic glossy, its tangent the
    /// constant world X).
    Plain {
        distribution: &'static str,
        roughness: Roughness,
        #[serde(skip_serializing_if = "Option::is_none")]
        anisotropy: Option<f64>,
    },
    /// A gloffuse group (the layered groups take an index, the anisotropic ones an
    /// anisotropy and the constant world X as their tangent).
    Group {
        group: String,
        roughness: Roughness,
        #[serde(skip_serializing_if = "Option::is_none")]
        ior: Option<f64>,
        #[serde(skip_serializing_if = "Option::is_none")]
        anisotropy: Option<f64>,
    },
    /// Mix Shader(Fac = Fresnel(ior), Diffuse, white Glossy of `distribution`).
    Mix {
        distribution: &'static str,
        roughness: Roughness,
        ior: f64,
    },
    /// Principled BSDF at its defaults, a dielectric of index `ior`.
    Principled { roughness: Roughness, ior: f64 },
    /// A Glass BSDF of index `ior` (on a solid sphere).
    Glass {
        distribution: &'static str,
        roughness: Roughness,
        ior: f64,
    },
    /// A Diffuse BSDF of the sweep's colour (roughness 0: Lambert).
    Diffuse { roughness: Roughness },
}

#[derive(Clone, Debug, Serialize)]
pub struct FurnaceSection {
    pub engine: Engine,
    /// Whole spheres that see themselves, each at its own depth, and 1,024 bounces (glass
    /// mode: light crosses a glass sphere's surfaces many times).
    pub solid: bool,
    pub cell: u32,
    pub columns: usize,
    pub samples: u32,
    pub seed: u32,
    pub radius_fraction: f64,
    /// Every sphere's colour (linear RGB).
    pub color: [f64; 3],
    pub output: String,
    pub threads: u32,
    pub spheres: Vec<SphereSpec>,
}

/// The verify job's parameter document: the generate fields, flattened, plus `furnace`.
#[derive(Clone, Debug, Serialize)]
pub struct FurnaceParams {
    #[serde(flatten)]
    pub generate: GenerateParams,
    pub furnace: FurnaceSection,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rs(values: &[f64]) -> Vec<Roughness> {
        values.iter().map(|&r| Roughness::new(r).unwrap()).collect()
    }

    /// Every row's id is its place, and its cells hold its distribution, roughness and
    /// index in the right roles; every reference cell holds a reference sphere.
    #[test]
    fn rows_name_their_cells() {
        let roughness = rs(&[0.0, 0.5, 1.0]);
        let ds = [Distribution::Ggx, Distribution::Beckmann];
        let blocks = [Block::Ior(1.33), Block::Anisotropy(0.5)];
        let plan = Plan::verify(&ds, &roughness, &blocks, RenderSettings::default());
        assert_eq!(plan.rows.len(), 2 * ds.len() * roughness.len());
        assert_eq!(plan.references.len(), 2 * roughness.len());
        for (i, row) in plan.rows.iter().enumerate() {
            assert_eq!(row.id, i);
            let expect = |role| Cell {
                role,
                roughness: row.roughness,
                block: row.block,
            };
            assert_eq!(
                plan.cells[row.uncorrected],
                expect(Role::Uncorrected(row.distribution))
            );
            assert_eq!(
                plan.cells[row.corrected],
                expect(Role::Corrected(row.distribution))
            );
        }
        // The verdict's order: per index, per distribution, per roughness.
        let order: Vec<_> = plan
            .rows
            .iter()
            .map(|r| (r.block, r.distribution, r.roughness.get()))
            .collect();
        assert_eq!(order[0], (Some(blocks[0]), Distribution::Ggx, 0.0));
        assert_eq!(order[4], (Some(blocks[0]), Distribution::Beckmann, 0.5));
        assert_eq!(order[6], (Some(blocks[1]), Distribution::Ggx, 0.0));
        for r in &plan.references {
            let c = &plan.cells[r.cell];
            assert_eq!(
                (c.role, c.roughness, c.block),
                (Role::Reference, r.roughness, r.block)
            );
        }
        // Each cell belongs to one row or reference at most.
        let mut used: Vec<usize> = plan
            .rows
            .iter()
            .flat_map(|r| [r.uncorrected, r.corrected])
            .chain(plan.references.iter().map(|r| r.cell))
            .collect();
        used.sort();
        used.dedup();
        assert_eq!(used.len(), plan.cells.len());
    }

    /// An index block is a glass block in glass mode (plain and reference spheres are Glass
    /// BSDFs) and a coat in layered mode (Mix Shader and Principled BSDF).
    #[test]
    fn an_index_block_is_glass_or_a_coat_by_mode() {
        let plan = Plan::verify(
            &[Distribution::Ggx],
            &rs(&[0.5]),
            &[Block::Ior(1.5)],
            RenderSettings::default(),
        );
        let group = |d: Distribution| format!("group {}", d.key());
        let spec = |cell: usize, mode| {
            serde_json::to_value(sphere_spec(&plan.cells[cell], mode, &group)).unwrap()
        };
        let (row, reference) = (plan.rows[0], plan.references[0].cell);
        let glass = serde_json::json!({"shader": "glass", "distribution": "GGX", "roughness": 0.5, "ior": 1.5});
        assert_eq!(spec(row.uncorrected, Mode::Glass), glass);
        assert_eq!(spec(reference, Mode::Glass)["distribution"], "MULTI_GGX");
        let corrected = spec(row.corrected, Mode::Glass);
        assert_eq!(
            (&corrected["shader"], &corrected["ior"]),
            (&"group".into(), &1.5.into())
        );
        assert_eq!(spec(row.uncorrected, Mode::Layered)["shader"], "mix");
        assert_eq!(spec(reference, Mode::Layered)["shader"], "principled");
    }

    #[test]
    fn eevee_lighting_cell_is_no_row() {
        let settings = RenderSettings::for_engine(Engine::Eevee);
        let plan = Plan::verify(&[Distribution::Ggx], &rs(&[0.5]), &[], settings);
        let lighting = plan.lighting().unwrap();
        assert_eq!(lighting, plan.cells.len() - 1);
        assert!(plan.rows.iter().all(|r| r.corrected != lighting));
        assert!(
            Plan::measure(&[Distribution::Ggx], &rs(&[0.5]), settings)
                .rows
                .is_empty()
        );
    }
}
