//! Study files. `--set` overrides and `[matrix]` axes are applied to the
//! TOML table; each expanded case is then deserialised into the typed
//! sections (the serde types are the one definition of every key, default
//! and unit) and validated once. Errors name the file, the dotted key and
//! what is allowed.

pub mod calibration;
mod expand;
pub mod labels;
mod mixture;
mod names;
mod overrides;

use expand::{ensemble_size, expand, extra_blocks, matrix_axes, replace_axes};
pub use mixture::MixtureSpec;
use mixture::{mixture_spec, DragTable};
use names::name_part;
use overrides::{flatten, parse_override, set_path};

use indexmap::IndexMap;
use monitor::MonitorConfig;
use serde::{Deserialize, Serialize};
use solver::multiphase::drag::{Drag, DragModel, DragUpdate};
use solver::remedies::{Descriptor, DESCRIPTORS};
use solver::{Material, Method, Perturb, Phase, Scene, SolverConfig, Wall};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use toml::{Table, Value};

/// A bad study file or override: names the file, the key and what is allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyError {
    pub file: String,
    pub key: String,
    pub message: String,
}

impl std::fmt::Display for StudyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}: key `{}`: {}", self.file, self.key, self.message)
        }
    }
}

impl std::error::Error for StudyError {}

/// The `[output]` table: what a case writes besides its summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Output {
    /// Target number of timeseries rows over the run.
    pub timeseries_rows: u64,
    /// Steps between ring checkpoints (0 = none).
    pub checkpoint_every: u64,
    /// Simulated times (s) at which particle VTK files are written; times
    /// past `scene.t_end` are allowed and never reached.
    pub vtk_times: Vec<f64>,
    /// End a case before t_end once its checks have their answers (the
    /// mode decay's fit window closed and followed on, docs/physics.md
    /// section 7); the summary's reason says when.
    pub end_when_checked: bool,
}

impl Default for Output {
    fn default() -> Self {
        Output {
            timeseries_rows: 1000,
            checkpoint_every: 20_000,
            vtk_times: vec![],
            end_when_checked: false,
        }
    }
}

impl Output {
    fn validate(&self) -> Result<(), KeyError> {
        let rows = self.timeseries_rows;
        if !(1..=10_000_000).contains(&rows) {
            return Err((
                "output.timeseries_rows".into(),
                format!("{rows} is out of range (allowed 1 ..= 10000000)"),
            ));
        }
        if let Some(t) = self
            .vtk_times
            .iter()
            .find(|t| !(t.is_finite() && **t >= 0.0))
        {
            return Err((
                "output.vtk_times".into(),
                format!("{t} is out of range (allowed finite times >= 0 s)"),
            ));
        }
        Ok(())
    }
}

/// One case's study file as written (the `[matrix]` table removed).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyDoc {
    #[serde(default)]
    #[allow(dead_code)]
    name: Option<String>,
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    scene: Scene,
    materials: IndexMap<String, Material>,
    #[serde(default)]
    method: Method,
    #[serde(default)]
    monitor: MonitorConfig,
    #[serde(default)]
    output: Output,
    #[serde(default)]
    perturb: Vec<Perturb>,
    drag: Option<DragTable>,
}

/// One expanded case of a study.
#[derive(Clone, Debug)]
pub struct Case {
    pub name: String,
    pub monitor: MonitorConfig,
    /// Every parameter by dotted key (after overrides and matrix values).
    pub params: BTreeMap<String, Value>,
    /// The resolved study table of this case (no matrix), written as case.toml.
    pub table: Table,
    pub solver: SolverConfig,
    pub output: Output,
    /// Some for a two-phase mixture: then `solver` holds every body and
    /// `phase_configs` splits them.
    pub mixture: Option<MixtureSpec>,
}

impl Case {
    /// Each phase's solver configuration (solid, fluid): the scene with only
    /// that phase's bodies.
    pub fn phase_configs(&self) -> [SolverConfig; 2] {
        Phase::ALL.map(|phase| {
            let mut cfg = self.solver.clone();
            cfg.scene.bodies.retain(|b| b.phase == Some(phase));
            cfg
        })
    }
}

#[derive(Clone, Debug)]
pub struct Study {
    pub file: PathBuf,
    pub cases: Vec<Case>,
    /// The `[calibration]` table, for `kick calibrate`.
    pub calibration: Option<calibration::CalibrationSpec>,
}

/// Reads, overrides, expands and validates a study file.
/// A TOML syntax error as "line L, column C: message" (1-based, columns
/// counted in characters), with the offending line quoted and a caret under
/// the column, so the reader need not count. Falls back to the bare message
/// when toml gives no span.
fn toml_error_message(text: &str, e: &toml::de::Error) -> String {
    let message = e
        .message()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ");
    let Some(span) = e.span() else {
        return format!("not valid TOML: {message}");
    };
    let (line, column) = line_column(text, span.start);
    let source = text.lines().nth(line - 1).unwrap_or("");
    let caret = format!("{}^", " ".repeat(column - 1));
    format!(
        "not valid TOML at line {line}, column {column}: {message}\n  {line:>4} | {source}\n       | {caret}"
    )
}

/// The 1-based line and column (in characters) of byte offset `at` in `text`.
fn line_column(text: &str, at: usize) -> (usize, usize) {
    let mut at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

pub fn load(path: &Path, overrides: &[String]) -> Result<Study, StudyError> {
    let file = path.display().to_string();
    let err = |key: &str, message: String| StudyError {
        file: file.clone(),
        key: key.to_string(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| err("", format!("cannot read: {e}")))?;
    let mut root: Table = text
        .parse()
        .map_err(|e: toml::de::Error| err("", toml_error_message(&text, &e)))?;
    for o in overrides {
        let (key, value) = parse_override(o).map_err(|m| err(o, m))?;
        set_path(&mut root, &key, value).map_err(|m| err(&key, m))?;
    }
    let mut matrix = root.remove("matrix");
    let calibration = root.remove("calibration");
    let ensemble = ensemble_size(&mut matrix).map_err(|(k, m)| err(&k, m))?;
    let extra = extra_blocks(&mut matrix).map_err(|(k, m)| err(&k, m))?;
    let axes = matrix_axes(matrix).map_err(|(k, m)| err(&k, m))?;
    let base = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "case".into());
    let mut cases = expand(&root, &axes, ensemble, &base).map_err(|(k, m)| err(&k, m))?;
    for (i, block) in extra.into_iter().enumerate() {
        let key = format!("matrix.also[{i}]");
        let axes = replace_axes(&axes, block, &key).map_err(|(k, m)| err(&k, m))?;
        for case in expand(&root, &axes, ensemble, &base).map_err(|(k, m)| err(&k, m))? {
            if cases.iter().any(|c| c.name == case.name) {
                let message = format!("case {} is already in the matrix", case.name);
                return Err(err(&key, message));
            }
            cases.push(case);
        }
    }
    let calibration = match calibration {
        None => None,
        Some(table) => {
            let spec = calibration::CalibrationSpec::from_toml(table);
            Some(spec.map_err(|(k, m)| err(&k, m))?)
        }
    };
    Ok(Study {
        file: path.to_path_buf(),
        cases,
        calibration,
    })
}

/// Relative position jitter (in h) of ensemble members unless `scene.jitter` is set.
pub const ENSEMBLE_JITTER: f64 = 1e-9;

/// The keys that tell ensemble members apart (not axes of a matrix).
pub const ENSEMBLE_KEYS: [&str; 2] = ["scene.seed", "scene.jitter"];

/// A bad key of a case: (dotted key, message).
type KeyError = (String, String);

/// A `[matrix]` axis: (dotted key, values).
type Axis = (String, Vec<Value>);

/// A serde error as (dotted key, message in the study file's words).
fn schema_error(e: serde_path_to_error::Error<toml::de::Error>) -> KeyError {
    let path = e.path().to_string();
    let mut path = if path == "." { String::new() } else { path };
    let mut message = e.inner().message().to_string();
    // A remedy's table reports "at `KEY`: ..." (serde loses the path there).
    while let Some(rest) = message.strip_prefix("at `") {
        let Some((key, rest)) = rest.split_once("`: ") else {
            break;
        };
        path = if path.is_empty() {
            key.to_string()
        } else {
            format!("{path}.{key}")
        };
        message = rest.to_string();
    }
    if let Some(rest) = message.strip_prefix("old key `") {
        if let Some((key, rest)) = rest.split_once("`: ") {
            let key = if path.is_empty() || path.ends_with(&format!(".{key}")) {
                if path.is_empty() {
                    key.to_string()
                } else {
                    path.clone()
                }
            } else {
                format!("{path}.{key}")
            };
            return (key, rest.to_string());
        }
    }
    let join = |field: &str| {
        if path.is_empty() || path.ends_with(&format!(".{field}")) || path == field {
            if path.is_empty() {
                field.to_string()
            } else {
                path.clone()
            }
        } else {
            format!("{path}.{field}")
        }
    };
    // serde's wording: "missing field `x`", "unknown field `x`, expected one of `a`, `b`",
    // "unknown variant `x`, expected one of `a`, `b`".
    let quoted: Vec<&str> = message.split('`').skip(1).step_by(2).collect();
    if message.starts_with("missing field") {
        let key = if path.is_empty() {
            quoted[0].to_string()
        } else {
            format!("{path}.{}", quoted[0])
        };
        (key, "is required".into())
    } else if message.starts_with("unknown field") {
        let allowed = quoted[1..].join(", ");
        (join(quoted[0]), format!("unknown key (allowed: {allowed})"))
    } else if message.starts_with("unknown variant") {
        let allowed = quoted[1..].join(" | ");
        (
            path,
            format!("\"{}\" is not allowed (allowed: {allowed})", quoted[0]),
        )
    } else {
        (path, message)
    }
}

#[cfg(test)]
mod tests {
    use super::expand::case;
    use super::*;

    fn toml(text: &str) -> Value {
        format!("v = {text}")
            .parse::<Table>()
            .unwrap()
            .remove("v")
            .unwrap()
    }

    /// The ghost surface's keys: `surface_level`, `min_surface_share` and
    /// `share_floor` read, their defaults, and a wrong level refused.
    #[test]
    fn the_ghost_surfaces_keys_parse() {
        let method: solver::Method = toml::from_str(
            "[projection]\nsurface_level = \"distance\"\nmin_surface_share = 0.2\nshare_floor = \"face_mass\"\n",
        )
        .unwrap();
        assert_eq!(method.projection.min_surface_share, 0.2);
        assert_eq!(method.projection.share_floor, solver::ShareFloor::FaceMass);
        assert_eq!(
            method.projection.surface_level,
            solver::SurfaceLevel::Distance
        );
        let defaults = solver::Method::default().projection;
        assert_eq!(defaults.surface_level, solver::SurfaceLevel::Fraction);
        assert_eq!(defaults.min_surface_share, 0.05);
        assert_eq!(defaults.share_floor, solver::ShareFloor::Fixed);
        assert!(
            toml::from_str::<solver::Method>("[projection]\nsurface_level = \"level_set\"\n")
                .is_err()
        );
    }

    /// The study file's spelling: `formulation = "pressure_implicit"`, `K =
    /// "inf"` (and TOML's bare inf), `[method.projection]` with its keys; a
    /// wrong key in the table is refused.
    #[test]
    fn the_pressure_implicit_keys_parse() {
        let method: solver::Method = toml::from_str(
            "formulation = \"pressure_implicit\"\n[projection]\ndrift = 0.2\ndrift_correction = \"position\"\npreconditioner = \"jacobi\"\n",
        )
        .unwrap();
        assert_eq!(method.formulation, solver::Formulation::PressureImplicit);
        assert_eq!(method.projection.drift, 0.2);
        assert_eq!(
            method.projection.drift_correction,
            solver::DriftCorrection::Position
        );
        assert_eq!(
            method.projection.preconditioner,
            solver::Preconditioner::Jacobi
        );
        assert!(toml::from_str::<solver::Method>("[projection]\ndrfit = 0.2\n").is_err());
        assert!(
            toml::from_str::<solver::Method>("[projection]\ndrift_correction = \"both\"\n")
                .is_err()
        );
        let method: solver::Method =
            toml::from_str("[projection]\npreconditioner = \"mic0\"\nadvection = \"bilinear\"\n")
                .unwrap();
        assert_eq!(
            method.projection.preconditioner,
            solver::Preconditioner::Mic0
        );
        assert_eq!(method.projection.advection, solver::Advection::Bilinear);
        assert!(toml::from_str::<solver::Method>("[projection]\nadvection = \"apic\"\n").is_err());
        for (text, surface) in [
            ("cell", solver::FreeSurface::Cell),
            ("ghost", solver::FreeSurface::Ghost),
            ("ghost_orthogonal", solver::FreeSurface::GhostOrthogonal),
        ] {
            let method: solver::Method = toml::from_str(&format!(
                "[projection]\nfree_surface = \"{text}\"\ndrift_depth = 2\n"
            ))
            .unwrap();
            assert_eq!(method.projection.free_surface, surface);
            assert_eq!(method.projection.drift_depth, 2);
        }
        assert!(
            toml::from_str::<solver::Method>("[projection]\nfree_surface = \"level_set\"\n")
                .is_err()
        );
        assert_eq!(
            solver::Method::default().projection.air_nodes,
            solver::AirNodes::Slaved
        );
        for (text, air_nodes) in [
            ("slaved", solver::AirNodes::Slaved),
            ("overwritten", solver::AirNodes::Overwritten),
        ] {
            let method: solver::Method =
                toml::from_str(&format!("[projection]\nair_nodes = \"{text}\"\n")).unwrap();
            assert_eq!(method.projection.air_nodes, air_nodes);
        }
        assert!(
            toml::from_str::<solver::Method>("[projection]\nair_nodes = \"dropped\"\n").is_err()
        );
        for text in ["K = \"inf\"", "K = inf"] {
            let m: solver::Material = toml::from_str(text).unwrap();
            assert_eq!(m.k, f64::INFINITY, "{text}");
        }
        assert!(toml::from_str::<solver::Material>("K = \"infinite\"").is_err());
        // Written back as "inf" (JSON has no infinity) and read again.
        let m: solver::Material = toml::from_str("K = \"inf\"").unwrap();
        let json = serde_json::to_string(&m).unwrap();
        assert!(json.contains("\"K\":\"inf\""), "{json}");
        let back: solver::Material = serde_json::from_str(&json).unwrap();
        assert_eq!(back.k, f64::INFINITY);
    }

    #[test]
    fn line_column_counts_lines_and_characters_from_one() {
        let text = "a = 1\nbé = 2\n\nc";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 4), (1, 5));
        assert_eq!(line_column(text, 6), (2, 1));
        // After the two-byte é, byte 9 is the third character; byte 8
        // (inside é) counts as é.
        assert_eq!(line_column(text, 9), (2, 3));
        assert_eq!(line_column(text, 8), (2, 2));
        assert_eq!(line_column(text, 14), (3, 1));
        assert_eq!(line_column(text, 15), (4, 1));
        assert_eq!(line_column(text, 99), (4, 2));
    }

    #[test]
    fn overrides_read_values_as_toml_and_bare_words_as_strings() {
        assert_eq!(
            parse_override("materials.water.K=1.5e6").unwrap(),
            ("materials.water.K".into(), Value::Float(1.5e6))
        );
        assert_eq!(
            parse_override(" scene.ppc = 3 ").unwrap(),
            ("scene.ppc".into(), Value::Integer(3))
        );
        assert_eq!(
            parse_override("method.shape=bspline2").unwrap().1,
            Value::String("bspline2".into())
        );
        assert_eq!(parse_override("a=[1, 2]").unwrap().1, toml("[1, 2]"));
        assert!(parse_override("no equals sign").is_err());
        assert!(parse_override("=3").is_err());
    }

    #[test]
    fn set_path_creates_tables_and_merges_table_values() {
        let mut root = Table::new();
        set_path(&mut root, "materials.water.K", Value::Float(1.0)).unwrap();
        set_path(
            &mut root,
            "materials.water.eos",
            Value::String("tait".into()),
        )
        .unwrap();
        set_path(&mut root, "materials.water", toml("{ gamma = 4.0 }")).unwrap();
        let water = root["materials"]["water"].as_table().unwrap();
        assert_eq!(water.len(), 3, "{water:?}");
        assert_eq!(water["K"], Value::Float(1.0));
        assert_eq!(water["gamma"], Value::Float(4.0));
        // A non-table value replaces; a path through a non-table is refused.
        set_path(&mut root, "materials.water.K", Value::Float(2.0)).unwrap();
        assert_eq!(root["materials"]["water"]["K"], Value::Float(2.0));
        assert!(set_path(&mut root, "materials.water.K.x", Value::Float(1.0)).is_err());
    }

    #[test]
    fn name_parts_are_short_and_readable() {
        assert_eq!(name_part("materials.water.K", &toml("1.5e6")), "K1.5MPa");
        assert_eq!(name_part("materials.water.K", &toml("15000")), "K15kPa");
        assert_eq!(name_part("materials.water.K", &toml("2e9")), "K2GPa");
        assert_eq!(
            name_part("materials.water.viscosity", &toml("0.5")),
            "mu0.5"
        );
        assert_eq!(name_part("method.dt", &toml("\"dynamic\"")), "dyn");
        assert_eq!(name_part("method.dt", &toml("\"fixed\"")), "fixed");
        assert_eq!(
            name_part("materials.water", &toml("{ eos = \"power\", gamma = 7.0 }")),
            "power-g7"
        );
        assert_eq!(name_part("method.cfl", &toml("0.1")), "cfl0.1");
        assert_eq!(name_part("drag.coefficient", &toml("3.2e5")), "B3.2e5");
        assert_eq!(name_part("method", &toml("{}")), "base");
        assert_eq!(name_part("scene.cell", &toml("0.005")), "h0.5cm");
        assert_eq!(
            name_part(
                "scene.body",
                &toml("[{ rect = [0.0, 0.0, 0.2, 0.2], flow = { kind = \"taylor_green\", amplitude = 0.01, mode = 2 } }]")
            ),
            "tg-m2"
        );
        assert_eq!(
            name_part(
                "scene.body",
                &toml("[{ rect = [0.0, 0.0, 0.2, 0.2], velocity = [0.5, 0.0], flow = { kind = \"grid_seed\", share = 1e-4, mode = 5 } }]")
            ),
            "U0.5x0_seed0.0001-m5"
        );
        assert_eq!(name_part("scene.no_slip", &toml("[]")), "slip");
        assert_eq!(
            name_part("scene.no_slip", &toml("[\"floor\"]")),
            "noslip-floor"
        );
        assert_eq!(name_part("method", &toml("{ f_reset = true }")), "f_reset");
        assert_eq!(name_part("scene.box", &toml("[0.8, 0.6]")), "box0.8x0.6");
        assert_eq!(
            name_part(
                "scene",
                &toml("{ box = [1.6, 0.4], body = [{ rect = [0.1, 0.0, 0.5, 0.2], material = \"water\" }] }")
            ),
            "box1.6x0.4-body0.4x0.2"
        );
    }

    #[test]
    fn an_ensemble_runs_each_case_as_seeded_members() {
        let dir = std::env::temp_dir().join(format!("kick-ensemble-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("e.toml");
        let text =
            "[scene]\n[[scene.body]]\nrect = [0.0, 0.0, 0.2, 0.4]\n[materials.water]\nK = 1e5\n\
                    [matrix]\nensemble = 3\n\"materials.water.K\" = [1e5, 1e6]\n";
        std::fs::write(&path, text).unwrap();
        let study = load(&path, &[]).unwrap();
        let names: Vec<&str> = study.cases.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "K100kPa_e0",
                "K100kPa_e1",
                "K100kPa_e2",
                "K1MPa_e0",
                "K1MPa_e1",
                "K1MPa_e2"
            ]
        );
        for (k, c) in study.cases.iter().enumerate() {
            assert_eq!(c.solver.scene.seed, (k % 3) as u64);
            assert_eq!(c.solver.scene.jitter, ENSEMBLE_JITTER);
            assert_eq!(c.params["scene.seed"], Value::Integer((k % 3) as i64));
        }
        std::fs::write(&path, text.replace("ensemble = 3", "ensemble = 0")).unwrap();
        let e = load(&path, &[]).unwrap_err();
        assert_eq!(e.key, "matrix.ensemble", "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Under the pressure-implicit formulation the keys it does not use
    /// (scheme, dt, j_update) are refused in the entry that switches it on
    /// and ignored, listed as `ignored.method.KEY`, when inherited.
    #[test]
    fn pressure_implicit_refuses_its_unused_keys_and_lists_inherited_ones() {
        let dir = std::env::temp_dir().join(format!("kick_implicit_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("s.toml");
        let base =
            "[scene]\n[[scene.body]]\nrect = [0.0, 0.0, 0.2, 0.4]\n[materials.water]\nK = 1e5\n\
                    [method]\nscheme = \"usf\"\ndt = \"fixed\"\n[matrix]\n";
        let inherited =
            format!("{base}\"method\" = [{{ }}, {{ formulation = \"pressure_implicit\" }}]\n");
        std::fs::write(&path, inherited).unwrap();
        let study = load(&path, &[]).unwrap();
        let implicit = &study.cases[1];
        assert_eq!(
            implicit.solver.method.formulation,
            solver::Formulation::PressureImplicit
        );
        assert_eq!(
            implicit.params["ignored.method.scheme"],
            Value::String("usf".into())
        );
        assert_eq!(
            implicit.params["ignored.method.dt"],
            Value::String("fixed".into())
        );
        assert!(!study.cases[0].params.contains_key("ignored.method.scheme"));
        // Its case.toml, read again (report, reproduce), is accepted.
        std::fs::write(&path, toml::to_string(&implicit.table).unwrap()).unwrap();
        let again = load(&path, &[]).unwrap();
        assert_eq!(again.cases[0].solver.method, implicit.solver.method);
        let own = format!(
            "{base}\"method\" = [{{ formulation = \"pressure_implicit\", j_update = \"exp\" }}]\n"
        );
        std::fs::write(&path, own).unwrap();
        assert_eq!(load(&path, &[]).unwrap_err().key, "method.j_update");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// `[[matrix.also]]` adds the main product with some axes' values
    /// replaced; it may not add an axis or repeat a case.
    #[test]
    fn matrix_also_blocks_add_cases_beside_the_product() {
        let dir = std::env::temp_dir().join(format!("kick_also_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("s.toml");
        let text =
            "[scene]\n[[scene.body]]\nrect = [0.0, 0.0, 0.2, 0.4]\n[materials.water]\nK = 1e5\n\
                    [matrix]\n\"method\" = [{ }]\n\"scene.cell\" = [0.02, 0.01]\n\
                    \"materials.water.K\" = [1e5, 1e6]\n\
                    [[matrix.also]]\n\"method\" = [{ j_bar = true }, { f_reset = true }]\n\
                    \"scene.cell\" = [0.01]\n";
        std::fs::write(&path, text).unwrap();
        let study = load(&path, &[]).unwrap();
        let names: Vec<&str> = study.cases.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "base_h2cm_K100kPa",
                "base_h2cm_K1MPa",
                "base_h1cm_K100kPa",
                "base_h1cm_K1MPa",
                "j_bar1.0_h1cm_K100kPa",
                "j_bar1.0_h1cm_K1MPa",
                "f_reset_h1cm_K100kPa",
                "f_reset_h1cm_K1MPa",
            ]
        );
        assert!(study.cases[4].solver.method.remedies.j_bar.is_some());
        assert_eq!(study.cases[7].solver.scene.cell, 0.01);
        let refused = |text: String| load_text(&path, &text).unwrap_err();
        let e = refused(text.replace("\"scene.cell\" = [0.01]", "\"scene.ppc\" = [3]"));
        assert_eq!(e.key, "matrix.also[0].scene.ppc", "{e}");
        assert!(e.message.contains("not an axis"), "{e}");
        let e = refused(text.replace("{ f_reset = true }", "{ }"));
        assert_eq!(e.key, "matrix.also[0]", "{e}");
        assert!(e.message.contains("base_h1cm_K100kPa"), "{e}");
        let e = refused(text.replace("\"scene.cell\" = [0.01]\n", "\"scene.cell\" = []\n"));
        assert_eq!(e.key, "matrix.also[0].scene.cell", "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn load_text(path: &Path, text: &str) -> Result<Study, StudyError> {
        std::fs::write(path, text).unwrap();
        load(path, &[])
    }

    const MIXTURE: &str = "[scene]\nbox = [0.1, 0.1]\ncell = 0.01\nperiodic = [true, true]\n\
        [[scene.body]]\nrect = [0.0, 0.0, 0.1, 0.1]\nmaterial = \"skeleton\"\nphase = \"solid\"\nfraction = 0.6\n\
        [[scene.body]]\nrect = [0.0, 0.0, 0.1, 0.1]\nmaterial = \"water\"\nphase = \"fluid\"\nfraction = 0.4\n\
        [materials.skeleton]\nK = 1e6\nshear_modulus = 3e5\n[materials.water]\nK = 1e5\nviscosity = 1e-3\n\
        [drag]\ncoefficient = 1e5\n";

    fn mixture_case(text: &str) -> Result<Case, KeyError> {
        case("c".into(), text.parse().unwrap())
    }

    #[test]
    fn a_drag_table_makes_a_mixture_split_by_phase() {
        let c = mixture_case(MIXTURE).unwrap();
        let spec = c.mixture.clone().expect("a mixture");
        assert_eq!(spec.drag.coefficient, 1e5);
        assert_eq!(spec.drag.update, DragUpdate::Implicit);
        assert!(!spec.fixed_solid);
        let [solid, fluid] = c.phase_configs();
        assert_eq!(solid.scene.bodies.len(), 1);
        assert_eq!(solid.scene.bodies[0].material, "skeleton");
        assert_eq!(fluid.scene.bodies[0].fraction, 0.4);
        // B = n^2 mu / k from the fluid's viscosity and fraction.
        let c =
            mixture_case(&MIXTURE.replace("coefficient = 1e5", "permeability = 1e-10")).unwrap();
        let b = c.mixture.unwrap().drag.coefficient;
        assert!((b / (0.16 * 1e-3 / 1e-10) - 1.0).abs() < 1e-12, "{b}");
    }

    /// With several faults, the bodies are reported first, then the drag
    /// coefficient, then the drag table's options.
    #[test]
    fn a_mixture_with_several_faults_reports_the_bodies_then_the_coefficient() {
        let bad = |text: &str| mixture_case(text).expect_err("refused").0;
        let fraction_and_coefficient = MIXTURE
            .replace("fraction = 0.4", "fraction = 0.5")
            .replace("coefficient = 1e5", "coefficient = -1.0");
        assert_eq!(bad(&fraction_and_coefficient), "scene.body[1].fraction");
        let coefficient_and_option = MIXTURE.replace(
            "coefficient = 1e5",
            "coefficient = -1.0\npore_node_average = true",
        );
        assert_eq!(bad(&coefficient_and_option), "drag.coefficient");
        let perturb = "[[perturb]]\nstep = 10\nregion = [0.0, 0.0, 0.05, 0.05]\ndv = [0.0, 1.0]\n";
        let phase_and_perturb = MIXTURE.replace("phase = \"fluid\"", "phase = \"solid\"") + perturb;
        assert_eq!(bad(&phase_and_perturb), "scene.body");
        let perturb_and_fraction = MIXTURE.replace("fraction = 0.4", "fraction = 0.5") + perturb;
        assert_eq!(bad(&perturb_and_fraction), "perturb");
    }

    #[test]
    fn bad_mixtures_name_the_key_and_what_is_allowed() {
        let bad = |text: &str| mixture_case(text).expect_err("refused");
        let (k, m) = bad(&MIXTURE.replace("[drag]\ncoefficient = 1e5\n", ""));
        assert_eq!(k, "scene.body[0].phase");
        assert!(m.contains("[drag]"), "{m}");
        let (k, m) = bad(&MIXTURE.replace("phase = \"fluid\"\n", ""));
        assert_eq!(k, "scene.body[1].phase");
        assert!(m.contains("solid | fluid"), "{m}");
        let (k, m) = bad(&MIXTURE.replace("phase = \"fluid\"", "phase = \"solid\""));
        assert_eq!(k, "scene.body");
        assert!(m.contains("none is fluid"), "{m}");
        let (k, m) = bad(&MIXTURE.replace("phase = \"fluid\"", "phase = \"gas\""));
        assert_eq!(k, "scene.body[1].phase");
        assert!(m.contains("solid | fluid"), "{m}");
        let (k, m) = bad(&MIXTURE.replace("fraction = 0.4", "fraction = 0.5"));
        assert_eq!(k, "scene.body[1].fraction");
        assert!(m.contains("n_s + n_f <= 1"), "{m}");
        let (k, m) = bad(&MIXTURE.replace(
            "coefficient = 1e5",
            "coefficient = 1e5\npermeability = 1e-10",
        ));
        assert_eq!(k, "drag");
        assert!(m.contains("exactly one"), "{m}");
        let (k, _) = bad(&MIXTURE.replace("coefficient = 1e5", "coefficient = -1.0"));
        assert_eq!(k, "drag.coefficient");
        let (k, m) = bad(&MIXTURE
            .replace("coefficient = 1e5", "permeability = 1e-10")
            .replace("viscosity = 1e-3", "viscosity = 0.0"));
        assert_eq!(k, "materials.water.viscosity");
        assert!(m.contains("permeability"), "{m}");
        let (k, _) = bad(&MIXTURE.replace(
            "coefficient = 1e5",
            "coefficient = 1e5\nkozeny_carman = 1.5",
        ));
        assert_eq!(k, "drag.kozeny_carman");
        let (k, m) = bad(&MIXTURE.replace("coefficient = 1e5", "coefficient = 1e5\nspeed = 3"));
        assert_eq!(k, "drag.speed");
        assert!(
            m.contains("unknown key") && m.contains("fixed_solid"),
            "{m}"
        );
        let (k, _) = bad(&MIXTURE.replace(
            "coefficient = 1e5",
            "coefficient = 1e5\ntop_traction = -1.0",
        ));
        assert_eq!(k, "drag.top_traction");
        let (k, m) = bad(&MIXTURE.replace(
            "coefficient = 1e5",
            "coefficient = 1e5\npore_pressure = true\nvolume_constraint = true",
        ));
        assert_eq!(k, "drag.volume_constraint");
        assert!(m.contains("pore_pressure"), "{m}");
        let (k, m) = bad(&MIXTURE.replace(
            "coefficient = 1e5",
            "coefficient = 1e5\npore_node_average = true",
        ));
        assert_eq!(k, "drag.pore_node_average");
        assert!(m.contains("pore_pressure = true"), "{m}");
        for model in ["bang_bang_particle", "svf_particle"] {
            let (k, m) = bad(&MIXTURE.replace(
                "coefficient = 1e5",
                &format!("coefficient = 1e5\nmodel = \"{model}\""),
            ));
            assert_eq!(k, "drag.update");
            assert!(m.contains("explicit"), "{m}");
        }
        let (k, m) =
            bad(&MIXTURE.replace("coefficient = 1e5", "coefficient = 1e5\nupdate = \"rk4\""));
        assert_eq!(k, "drag.update");
        assert!(m.contains("explicit | implicit | exponential"), "{m}");
        // Drained walls: with the pore pressure, on a wall that exists, not also no-slip.
        let walled = MIXTURE.replace("periodic = [true, true]", "periodic = [true, false]");
        let (k, m) = bad(&walled.replace(
            "coefficient = 1e5",
            "coefficient = 1e5\ndrained = [\"top\"]",
        ));
        assert_eq!(k, "drag.drained");
        assert!(m.contains("pore_pressure"), "{m}");
        let (k, m) = bad(&walled.replace(
            "coefficient = 1e5",
            "coefficient = 1e5\npore_pressure = true\ndrained = [\"left\"]",
        ));
        assert_eq!(k, "drag.drained");
        assert!(m.contains("periodic"), "{m}");
        let (k, m) = bad(&walled
            .replace("cell = 0.01", "cell = 0.01\nno_slip = [\"top\"]")
            .replace(
                "coefficient = 1e5",
                "coefficient = 1e5\npore_pressure = true\ndrained = [\"top\"]",
            ));
        assert_eq!(k, "drag.drained");
        assert!(m.contains("no_slip"), "{m}");
        let drained = mixture_case(&walled.replace(
            "coefficient = 1e5",
            "coefficient = 1e5\npore_pressure = true\ndrained = [\"top\"]\ndrained_pressure = 200.0",
        ))
        .unwrap()
        .mixture
        .unwrap();
        assert_eq!(drained.drained, vec![Wall::Top]);
        assert_eq!(drained.drained_pressure, 200.0);
        // Inflow walls: with the pore pressure, a speed > 0, not also drained.
        let inflow =
            |keys: &str| walled.replace("coefficient = 1e5", &format!("coefficient = 1e5\n{keys}"));
        for (keys, key, says) in [
            ("inflow = [\"floor\"]\ninflow_velocity = 0.1", "drag.inflow", "pore_pressure"),
            (
                "pore_pressure = true\ninflow = [\"floor\"]\ninflow_velocity = 0.0",
                "drag.inflow_velocity",
                "> 0",
            ),
            (
                "pore_pressure = true\ndrained = [\"floor\"]\ninflow = [\"floor\"]\ninflow_velocity = 0.1",
                "drag.inflow",
                "both drained and an inflow",
            ),
        ] {
            let (k, m) = bad(&inflow(keys));
            assert_eq!(k, key, "{keys}: {m}");
            assert!(m.contains(says), "{m}");
        }
        let fed = mixture_case(&inflow(
            "pore_pressure = true\ndrained = [\"top\"]\ninflow = [\"floor\"]\ninflow_velocity = 0.1",
        ))
        .unwrap()
        .mixture
        .unwrap();
        assert_eq!(fed.inflow, vec![Wall::Floor]);
        assert_eq!(fed.inflow_velocity, 0.1);
    }

    #[test]
    fn serde_errors_become_dotted_keys_and_allowed_values() {
        let bad = |text: &str| -> KeyError {
            let table: Table = text.parse().unwrap();
            case("c".into(), table).expect_err("refused")
        };
        let good =
            "[scene]\n[[scene.body]]\nrect = [0.0, 0.0, 0.2, 0.4]\n[materials.water]\nK = 1e5\n";
        assert!(case("c".into(), good.parse().unwrap()).is_ok());
        let (k, m) = bad(&good.replace("K = 1e5", "K = 1e5\nnu = 3"));
        assert_eq!(k, "materials.water.nu");
        assert!(m.contains("unknown key") && m.contains("viscosity"), "{m}");
        let (k, m) = bad(&good.replace("K = 1e5", "eos = \"ideal\"\nK = 1e5"));
        assert_eq!(k, "materials.water.eos");
        assert!(
            m.contains("\"ideal\"") && m.contains("power | tait | linear"),
            "{m}"
        );
        let (k, m) = bad(&good.replace("K = 1e5", "rho0 = 1.0"));
        assert_eq!(
            (k.as_str(), m.as_str()),
            ("materials.water.K", "is required")
        );
        let (k, m) = bad(&good.replace("rect = [0.0, 0.0, 0.2, 0.4]", "velocity = [1, 0]"));
        assert_eq!(
            (k.as_str(), m.as_str()),
            ("scene.body[0].rect", "is required")
        );
        let (k, _) = bad(&format!("{good}[method]\ncfl = \"high\"\n"));
        assert_eq!(k, "method.cfl");
        let (k, m) = bad("[materials.water]\nK = 1e5\n");
        assert_eq!((k.as_str(), m.as_str()), ("scene", "is required"));
    }

    /// A remedy written with its table gets the name its old flat keys gave.
    #[test]
    fn remedy_tables_are_named_as_their_old_flat_keys() {
        let named = |text: &str| name_part("method", &toml(text));
        for (new, old) in [
            ("{ j_bar = true }", "j_bar1.0"),
            ("{ j_bar = {} }", "j_bar1.0"),
            ("{ j_bar = { blend = 0.5 } }", "j_bar0.5"),
            (
                "{ j_bar = { fit = \"linear\" }, bulk_damping = { coefficient = 0.3 } }",
                "j_bar1.0-linear-bulk_damping0.3",
            ),
            (
                "{ j_bar = { average_increment = true }, bulk_damping = true }",
                "j_bar1.0-average_increment-bulk_damping0.3",
            ),
            ("{ j_bar = { carry = false } }", "j_bar1.0-no_carry_averaged_j"),
            (
                "{ transfer = \"flip\", pic_damping = { time = 5e-5 }, shifting = { time = 0.02, surface_share = 0.25 }, ppc = 3 }",
                "flip-pic_damping_time0.00005-shift_time0.02-shift_surface_share0.25-ppc3",
            ),
            ("{ volume_relaxation = { time = 0.16 } }", "volume_relaxation_time0.16"),
            ("{ min_node_mass = { share = 0.01 } }", "min_node_mass0.01"),
            ("{ grid_damping = true }", "grid_damping5.0"),
            ("{ grid_damping = { coefficient = 2 } }", "grid_damping2"),
            ("{ cell_dilatation = true }", "cell_dilatation1.0"),
            ("{ f_reset = true }", "f_reset"),
            ("{ force = \"mls\", f_reset = {} }", "mls-f_reset"),
            ("{ null_space_filter = true }", "null_space_filter"),
        ] {
            assert_eq!(named(new), old, "{new}");
        }
        // A matrix axis that switches a remedy off and on.
        assert_eq!(name_part("method.j_bar", &toml("false")), "j_bar0.0");
        assert_eq!(name_part("method.j_bar", &toml("true")), "j_bar1.0");
        assert_eq!(name_part("method.f_reset", &toml("false")), "no_f_reset");
        // Switched on with its defaults, a remedy is never named like the plain method.
        assert_ne!(named("{ pressure_smoothing = true }"), named("{ }"));
    }

    #[test]
    fn old_flat_remedy_keys_are_refused_naming_the_new_key() {
        let good =
            "[scene]\n[[scene.body]]\nrect = [0.0, 0.0, 0.2, 0.4]\n[materials.water]\nK = 1e5\n";
        let bad = |method: &str| -> KeyError {
            let text = format!("{good}[method]\n{method}\n");
            case("c".into(), text.parse().unwrap()).expect_err("refused")
        };
        let (k, m) = bad("j_bar_fit = \"linear\"");
        assert_eq!(k, "method.j_bar_fit");
        assert!(m.contains("[method.j_bar] fit"), "{m}");
        let (k, m) = bad("shift_time = 0.02");
        assert_eq!(k, "method.shift_time");
        assert!(m.contains("[method.shifting] time"), "{m}");
        let (k, m) = bad("carry_averaged_j = false");
        assert_eq!(k, "method.carry_averaged_j");
        assert!(m.contains("carry"), "{m}");
        let (k, m) = bad("j_bar = 1.0");
        assert_eq!(k, "method.j_bar");
        assert!(m.contains("[method.j_bar] blend = 1.0"), "{m}");
        let (k, m) = bad("min_node_mass = 0.01");
        assert_eq!(k, "method.min_node_mass");
        assert!(m.contains("[method.min_node_mass] share = 0.01"), "{m}");
        let (k, m) = bad("[method.j_bar]\nbogus = 1");
        assert_eq!(k, "method.j_bar.bogus");
        assert!(m.contains("unknown key") && m.contains("fit"), "{m}");
        let (k, m) = bad("bogus = 1");
        assert_eq!(k, "method.bogus");
        assert!(m.contains("j_bar") && m.contains("cfl"), "{m}");
        let (k, m) = bad("[method.shifting]\ntime = -1.0");
        assert_eq!(k, "method.shifting.time");
        assert!(m.contains("out of range"), "{m}");
        // The new keys are read.
        let text =
            format!("{good}[method]\nshape = \"bspline2\"\n[method.j_bar]\nfit = \"linear\"\n");
        let c = case("c".into(), text.parse().unwrap()).unwrap();
        let j_bar = c.solver.method.remedies.j_bar.expect("j_bar on");
        assert_eq!(j_bar.fit, solver::JBarFit::Linear);
        assert_eq!(c.params["method.j_bar.blend"], Value::Float(1.0));
    }

    /// Every shipped study expands to unique case names.
    #[test]
    fn method_ppc_overrides_the_scene_seeding_and_names_itself() {
        let text = "[scene]\nppc = 2\n[[scene.body]]\nrect = [0.0, 0.0, 0.2, 0.4]\n\
            [materials.water]\nK = 1e5\n[method]\nppc = 3\n";
        let c = case("c".into(), text.parse().unwrap()).unwrap();
        assert_eq!(c.solver.scene.ppc, 3);
        assert_eq!(c.params["method.ppc"], Value::Integer(3));
        assert_eq!(c.params["scene.ppc"], Value::Integer(3));
        // The written case table keeps the key, so a reload seeds the same.
        assert_eq!(c.table["method"]["ppc"], Value::Integer(3));
        let plain = case("c".into(), text.replace("ppc = 3\n", "").parse().unwrap()).unwrap();
        assert_eq!(plain.solver.scene.ppc, 2);
        assert!(!plain.params.contains_key("method.ppc"));
        for bad in ["0", "9", "2.5", "\"3\""] {
            let t = text.replace("ppc = 3", &format!("ppc = {bad}"));
            let (k, m) = case("c".into(), t.parse().unwrap()).expect_err("refused");
            assert_eq!(k, "method.ppc");
            assert!(m.contains("1 ..= 8"), "{m}");
        }
        assert_eq!(name_part("method", &toml("{ ppc = 3 }")), "ppc3");
    }
}
