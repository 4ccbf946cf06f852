//! Study files. `--set` overrides and `[matrix]` axes are applied to the
//! TOML table; each expanded case is then deserialised into the typed
//! sections (the serde types are the one definition of every key, default
//! and unit) and validated once. Errors name the file, the dotted key and
//! what is allowed.

pub mod labels;

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

/// The `[drag]` table: the scene is a two-phase mixture (docs/physics.md
/// section 6) whose bodies each name their `phase`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DragTable {
    /// B (kg m^-3 s^-1), the drag per mixture volume per unit relative velocity.
    coefficient: Option<f64>,
    /// Or the skeleton's permeability k (m^2): B = n^2 mu / k with the fluid
    /// material's viscosity mu and the fluid bodies' fraction n.
    permeability: Option<f64>,
    /// Kozeny-Carman scaling of B with the nodal porosity, from this reference porosity.
    kozeny_carman: Option<f64>,
    #[serde(default)]
    model: DragModel,
    #[serde(default)]
    update: DragUpdate,
    /// The solid is a fixed skeleton (its grid velocity held at zero).
    #[serde(default)]
    fixed_solid: bool,
    /// The fluid's pressure on the grid from each node's volume balance
    /// (grains incompressible; the fluid's material is the pore fluid).
    #[serde(default)]
    pore_pressure: bool,
    /// The pore pressure averaged over each node's neighbours ([1 2 1] / 4
    /// per axis), which removes its node-to-node mode (needs pore_pressure).
    #[serde(default)]
    pore_node_average: bool,
    /// The volume constraint n_s + n_f <= 1 per node (the fluid keeps its
    /// own pressure; not with pore_pressure, which balances volumes already).
    #[serde(default)]
    volume_constraint: bool,
    /// A downward traction (Pa) on the solid's top surface.
    #[serde(default)]
    top_traction: f64,
    /// Seconds over which that traction ramps up from 0.
    #[serde(default)]
    traction_ramp: f64,
    /// Drained walls (e.g. ["top"]): the pore pressure is `drained_pressure`
    /// there and the wall is open (what crosses it flows out).
    #[serde(default)]
    drained: Vec<Wall>,
    /// The pore pressure (Pa) on the drained walls.
    #[serde(default)]
    drained_pressure: f64,
    /// Inflow walls (e.g. ["floor"]): the water enters through them at
    /// `inflow_velocity`; open to the water, a wall to the grains.
    #[serde(default)]
    inflow: Vec<Wall>,
    /// The water's speed into the box (m/s) through the inflow walls.
    #[serde(default)]
    inflow_velocity: f64,
}

/// A mixture case's interaction: the resolved `[drag]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct MixtureSpec {
    pub drag: Drag,
    pub fixed_solid: bool,
    pub pore_pressure: bool,
    pub pore_node_average: bool,
    pub volume_constraint: bool,
    pub top_traction: f64,
    pub traction_ramp: f64,
    pub drained: Vec<Wall>,
    pub drained_pressure: f64,
    pub inflow: Vec<Wall>,
    pub inflow_velocity: f64,
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
    Ok(Study {
        file: path.to_path_buf(),
        cases,
    })
}

/// Relative position jitter (in h) of ensemble members unless `scene.jitter` is set.
pub const ENSEMBLE_JITTER: f64 = 1e-9;

/// The keys that tell ensemble members apart (not axes of a matrix).
pub const ENSEMBLE_KEYS: [&str; 2] = ["scene.seed", "scene.jitter"];

/// The cases of one product of `axes` over `root`, in axis order (the
/// last axis varies fastest), each ensemble member a case of its own.
fn expand(
    root: &Table,
    axes: &[Axis],
    ensemble: Option<u64>,
    base: &str,
) -> Result<Vec<Case>, KeyError> {
    let total: usize = axes.iter().map(|(_, v)| v.len()).product();
    let mut cases = vec![];
    for index in 0..total {
        let mut table = root.clone();
        let mut rest = index;
        let mut name_parts = vec![];
        // The method keys this case's matrix entries set (its own entry).
        let mut entry_keys = BTreeSet::new();
        for (key, values) in axes.iter().rev() {
            let v = &values[rest % values.len()];
            rest /= values.len();
            set_path(&mut table, key, v.clone()).map_err(|m| (format!("matrix.{key}"), m))?;
            name_parts.push(name_part(key, v));
            match (key.as_str(), v) {
                ("method", Value::Table(t)) => entry_keys.extend(t.keys().cloned()),
                (k, _) => {
                    if let Some(rest) = k.strip_prefix("method.") {
                        entry_keys.insert(rest.split('.').next().unwrap_or(rest).to_string());
                    }
                }
            }
        }
        let ignored = formulation_keys(root, &table, &entry_keys)?;
        // The case's own table (written as case.toml, read again by report,
        // reproduce and explain) leaves them out: there they would be the
        // formulation's own entry.
        if let Some(Value::Table(method)) = table.get_mut("method") {
            for (key, _) in &ignored {
                method.remove(key.trim_start_matches("method."));
            }
        }
        name_parts.reverse();
        let name = if name_parts.is_empty() {
            base.to_string()
        } else {
            name_parts.join("_")
        };
        let with_ignored = |mut c: Case| {
            for (key, value) in &ignored {
                c.params.insert(format!("ignored.{key}"), value.clone());
            }
            c
        };
        let Some(n) = ensemble else {
            cases.push(with_ignored(case(name, table)?));
            continue;
        };
        for member in 0..n {
            let mut table = table.clone();
            let scene = table
                .entry("scene")
                .or_insert_with(|| Value::Table(Table::new()));
            if let Value::Table(scene) = scene {
                scene
                    .entry("jitter")
                    .or_insert(Value::Float(ENSEMBLE_JITTER));
                // Members K of a base seed s: seeds s + K.
                let base = scene.get("seed").and_then(Value::as_integer).unwrap_or(0);
                scene.insert("seed".into(), Value::Integer(base + member as i64));
            }
            cases.push(with_ignored(case(format!("{name}_e{member}"), table)?));
        }
    }
    Ok(cases)
}

/// The method keys the pressure-implicit formulation does not use: it has
/// its own order of stages, its own J update and takes dt from the flow.
const UNUSED_BY_PRESSURE_IMPLICIT: [&str; 3] = ["scheme", "dt", "j_update"];

/// Under `formulation = "pressure_implicit"`, a key it does not use is
/// refused when the formulation's own entry sets it (the matrix entry that
/// switches it on, or the base `[method]` when that does), and ignored when
/// inherited from the base: returned as (key, value) for the summary.
fn formulation_keys(
    root: &Table,
    table: &Table,
    entry_keys: &BTreeSet<String>,
) -> Result<Vec<(String, Value)>, KeyError> {
    let method_of = |t: &Table| t.get("method").and_then(Value::as_table).cloned();
    let Some(method) = method_of(table) else {
        return Ok(vec![]);
    };
    if method.get("formulation").and_then(Value::as_str) != Some("pressure_implicit") {
        return Ok(vec![]);
    }
    let own: BTreeSet<String> = if entry_keys.contains("formulation") {
        entry_keys.clone()
    } else {
        let base = method_of(root).unwrap_or_default();
        base.keys()
            .cloned()
            .chain(entry_keys.iter().cloned())
            .collect()
    };
    let mut ignored = vec![];
    for key in UNUSED_BY_PRESSURE_IMPLICIT {
        let Some(value) = method.get(key) else {
            continue;
        };
        if own.contains(key) {
            return Err((
                format!("method.{key}"),
                "is not used by formulation = \"pressure_implicit\" (its own order of stages and J update, dt from the flow): leave it out of the entry that sets the formulation".into(),
            ));
        }
        ignored.push((format!("method.{key}"), value.clone()));
    }
    Ok(ignored)
}

/// `[[matrix.also]]`: further blocks of cases, each the main product with
/// some axes' values replaced (e.g. every remedy at one cell size beside
/// the baselines at three), so a study need not run the full product.
fn extra_blocks(matrix: &mut Option<Value>) -> Result<Vec<Table>, KeyError> {
    let Some(Value::Table(t)) = matrix else {
        return Ok(vec![]);
    };
    match t.remove("also") {
        None => Ok(vec![]),
        Some(Value::Array(blocks)) => blocks
            .into_iter()
            .enumerate()
            .map(|(i, b)| match b {
                Value::Table(b) if !b.is_empty() => Ok(b),
                _ => Err((
                    format!("matrix.also[{i}]"),
                    "must be a table of axis = [values] (write [[matrix.also]])".into(),
                )),
            })
            .collect(),
        Some(_) => Err((
            "matrix.also".into(),
            "must be an array of tables (write [[matrix.also]])".into(),
        )),
    }
}

/// The main axes with a block's values in place of theirs; a block may only
/// replace axes of `[matrix]`, so every case's name has the same parts.
fn replace_axes(axes: &[Axis], block: Table, key: &str) -> Result<Vec<Axis>, KeyError> {
    let mut replaced = axes.to_vec();
    for (axis, values) in matrix_axes(Some(Value::Table(block)))
        .map_err(|(k, m)| (k.replacen("matrix", key, 1), m))?
    {
        let Some(slot) = replaced.iter_mut().find(|(k, _)| *k == axis) else {
            let names: Vec<&str> = axes.iter().map(|(k, _)| k.as_str()).collect();
            return Err((
                format!("{key}.{axis}"),
                format!(
                    "is not an axis of [matrix] (a block replaces the values of: {})",
                    names.join(", ")
                ),
            ));
        };
        slot.1 = values;
    }
    Ok(replaced)
}

/// `[matrix] ensemble = N`: every case runs as N members `CASE_e0 .. CASE_e{N-1}`,
/// each with its own `scene.seed` (and `scene.jitter`, default `ENSEMBLE_JITTER`).
fn ensemble_size(matrix: &mut Option<Value>) -> Result<Option<u64>, KeyError> {
    let Some(Value::Table(t)) = matrix else {
        return Ok(None);
    };
    match t.remove("ensemble") {
        None => Ok(None),
        Some(Value::Integer(n)) if (1..=1000).contains(&n) => Ok(Some(n as u64)),
        Some(other) => Err((
            "matrix.ensemble".into(),
            format!("{other} is out of range (allowed whole numbers 1 ..= 1000)"),
        )),
    }
}

/// A bad key of a case: (dotted key, message).
type KeyError = (String, String);

/// A `[matrix]` axis: (dotted key, values).
type Axis = (String, Vec<Value>);

/// The `[matrix]` table as axes, in file order.
fn matrix_axes(matrix: Option<Value>) -> Result<Vec<Axis>, KeyError> {
    let table = match matrix {
        None => return Ok(vec![]),
        Some(Value::Table(t)) => t,
        Some(_) => return Err(("matrix".into(), "must be a table of key = [values]".into())),
    };
    table
        .into_iter()
        .map(|(key, values)| match values {
            Value::Array(v) if !v.is_empty() => Ok((key, v)),
            Value::Array(_) => Err((format!("matrix.{key}"), "needs at least one value".into())),
            _ => Err((format!("matrix.{key}"), "must be an array of values".into())),
        })
        .collect()
}

/// `method.ppc`: the seeding density as a choice of method (a matrix's
/// method entry can then refine one method's particles), written into
/// `scene.ppc` before the case is read. Returns the effective table and the
/// value, if set.
fn method_ppc(table: &Table) -> Result<(Table, Option<Value>), KeyError> {
    let mut table = table.clone();
    let Some(Value::Table(method)) = table.get_mut("method") else {
        return Ok((table, None));
    };
    let Some(ppc) = method.remove("ppc") else {
        return Ok((table, None));
    };
    match ppc {
        Value::Integer(n) if (1..=8).contains(&n) => {
            set_path(&mut table, "scene.ppc", ppc.clone()).map_err(|m| ("scene.ppc".into(), m))?;
            Ok((table, Some(ppc)))
        }
        other => Err((
            "method.ppc".into(),
            format!(
                "{other} is out of range (allowed whole numbers 1 ..= 8; it overrides scene.ppc)"
            ),
        )),
    }
}

/// Deserialises and validates one case's table.
fn case(name: String, table: Table) -> Result<Case, KeyError> {
    let (effective, ppc) = method_ppc(&table)?;
    let doc: StudyDoc =
        serde_path_to_error::deserialize(Value::Table(effective)).map_err(schema_error)?;
    let mut scene = doc.scene;
    scene.materials = doc
        .materials
        .into_iter()
        .map(|(name, m)| Material { name, ..m })
        .collect();
    let solver = SolverConfig {
        scene,
        method: doc.method,
        perturb: doc.perturb,
    };
    solver.validate().map_err(|e| (e.key, e.message))?;
    doc.monitor
        .validate()
        .map_err(|(k, m)| (format!("monitor.{k}"), m))?;
    doc.output.validate()?;
    let mixture = match doc.drag {
        Some(drag) => Some(mixture_spec(&drag, &solver)?),
        None => {
            if let Some(i) = solver.scene.bodies.iter().position(|b| b.phase.is_some()) {
                return Err((
                    format!("scene.body[{i}].phase"),
                    "needs a [drag] table (a mixture); leave it out for one phase".into(),
                ));
            }
            None
        }
    };
    let mut params = flatten(&table);
    if let Some(ppc) = ppc {
        params.insert("scene.ppc".into(), ppc);
    }
    // Every method key appears in every case, defaults included (a remedy
    // switched on with every one of its settings).
    if let Ok(Value::Table(m)) = Value::try_from(&solver.method) {
        for (k, v) in flatten(&m) {
            params.entry(format!("method.{k}")).or_insert(v);
        }
    }
    Ok(Case {
        name,
        monitor: doc.monitor,
        params,
        table,
        solver,
        output: doc.output,
        mixture,
    })
}

/// Checks a mixture's bodies and resolves its `[drag]` table.
fn mixture_spec(t: &DragTable, solver: &SolverConfig) -> Result<MixtureSpec, KeyError> {
    mixture_bodies(solver)?;
    let coefficient = drag_coefficient(t, solver)?;
    check_drag_options(t, solver)?;
    Ok(MixtureSpec {
        drag: Drag {
            coefficient,
            kozeny_carman: t.kozeny_carman,
            model: t.model,
            update: t.update,
        },
        fixed_solid: t.fixed_solid,
        pore_pressure: t.pore_pressure,
        pore_node_average: t.pore_node_average,
        volume_constraint: t.volume_constraint,
        top_traction: t.top_traction,
        traction_ramp: t.traction_ramp,
        drained: t.drained.clone(),
        drained_pressure: t.drained_pressure,
        inflow: t.inflow.clone(),
        inflow_velocity: t.inflow_velocity,
    })
}

/// A body of each phase, every body with one, no perturbation, and no
/// overlap but of the two phases with n_s + n_f <= 1.
fn mixture_bodies(solver: &SolverConfig) -> Result<(), KeyError> {
    let bodies = &solver.scene.bodies;
    if let Some(i) = bodies.iter().position(|b| b.phase.is_none()) {
        return Err((
            format!("scene.body[{i}].phase"),
            "is required in a mixture (allowed: solid | fluid)".into(),
        ));
    }
    for phase in Phase::ALL {
        if !bodies.iter().any(|b| b.phase == Some(phase)) {
            return Err((
                "scene.body".into(),
                format!(
                    "a mixture needs a body of each phase: none is {}",
                    phase.name()
                ),
            ));
        }
    }
    if !solver.perturb.is_empty() {
        return Err((
            "perturb".into(),
            "is not available in a mixture yet (allowed: single-phase scenes)".into(),
        ));
    }
    overlaps(bodies)
}

/// Overlapping bodies of the two phases share the volume: n_s + n_f <= 1;
/// two bodies of one phase may not overlap.
fn overlaps(bodies: &[solver::Body]) -> Result<(), KeyError> {
    for (i, a) in bodies.iter().enumerate() {
        for (j, b) in bodies.iter().enumerate().skip(i + 1) {
            let overlap = a.rect[0] < b.rect[2]
                && b.rect[0] < a.rect[2]
                && a.rect[1] < b.rect[3]
                && b.rect[1] < a.rect[3];
            if overlap && a.phase != b.phase {
                if a.fraction + b.fraction > 1.0 + 1e-12 {
                    return Err((
                        format!("scene.body[{j}].fraction"),
                        format!(
                            "{} with body {i}'s {} over the same ground exceeds 1 (allowed: n_s + n_f <= 1)",
                            b.fraction, a.fraction
                        ),
                    ));
                }
            } else if overlap {
                return Err((
                    format!("scene.body[{j}].rect"),
                    format!("overlaps body {i} of the same phase (allowed: one body per phase and place)"),
                ));
            }
        }
    }
    Ok(())
}

/// The drag coefficient B (kg m^-3 s^-1): `drag.coefficient`, or from
/// `drag.permeability` and the fluid's viscosity and fraction.
fn drag_coefficient(t: &DragTable, solver: &SolverConfig) -> Result<f64, KeyError> {
    let bodies = &solver.scene.bodies;
    let positive = |key: &str, v: f64| {
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err((
                key.to_string(),
                format!("{v} is out of range (allowed: finite > 0)"),
            ))
        }
    };
    match (t.coefficient, t.permeability) {
        (Some(b), None) => {
            if b >= 0.0 && b.is_finite() {
                Ok(b)
            } else {
                Err((
                    "drag.coefficient".into(),
                    format!("{b} is out of range (allowed: finite >= 0 kg m^-3 s^-1)"),
                ))
            }
        }
        (None, Some(k)) => {
            let k = positive("drag.permeability", k)?;
            let fluid = bodies
                .iter()
                .find(|b| b.phase == Some(Phase::Fluid))
                .expect("checked above");
            let material = solver.scene.material_index(fluid).expect("validated");
            let mu = solver.scene.materials[material].viscosity;
            if mu <= 0.0 {
                return Err((
                    format!("materials.{}.viscosity", solver.scene.materials[material].name),
                    format!("{mu}: drag.permeability needs the fluid's viscosity > 0 (or give drag.coefficient)"),
                ));
            }
            Ok(Drag::from_permeability(mu, k, fluid.fraction))
        }
        _ => Err((
            "drag".into(),
            "give exactly one of `coefficient` (kg m^-3 s^-1) and `permeability` (m^2)".into(),
        )),
    }
}

/// The drag table's options agree with one another and with the scene's
/// walls: the update, volume constraint, pore pressure, drained and inflow
/// walls, Kozeny-Carman porosity and the top traction.
fn check_drag_options(t: &DragTable, solver: &SolverConfig) -> Result<(), KeyError> {
    if t.model.is_particle_based() && t.update != DragUpdate::Explicit {
        return Err((
            "drag.update".into(),
            "the particle-based model is explicit (allowed: explicit)".into(),
        ));
    }
    if t.volume_constraint && t.pore_pressure {
        return Err((
            "drag.volume_constraint".into(),
            "not with pore_pressure = true, whose volume balance holds the constraint already (allowed: one of them)".into(),
        ));
    }
    if t.pore_node_average && !t.pore_pressure {
        return Err((
            "drag.pore_node_average".into(),
            "it needs drag.pore_pressure = true (allowed: false without it)".into(),
        ));
    }
    solver::multiphase::mixture::check_drained(
        &solver.scene,
        &t.drained,
        t.drained_pressure,
        t.pore_pressure,
    )
    .map_err(|e| (e.key, e.message))?;
    solver::multiphase::mixture::check_inflow(
        &solver.scene,
        &t.inflow,
        t.inflow_velocity,
        t.pore_pressure,
        Wall::mask(&t.drained),
    )
    .map_err(|e| (e.key, e.message))?;
    if let Some(n0) = t.kozeny_carman {
        if !(n0 > 0.0 && n0 < 1.0) {
            return Err((
                "drag.kozeny_carman".into(),
                format!("{n0} is out of range (allowed: a reference porosity in (0, 1))"),
            ));
        }
    }
    for (key, v) in [
        ("drag.top_traction", t.top_traction),
        ("drag.traction_ramp", t.traction_ramp),
    ] {
        if !(v >= 0.0 && v.is_finite()) {
            return Err((
                key.into(),
                format!("{v} is out of range (allowed: finite >= 0)"),
            ));
        }
    }
    Ok(())
}

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

/// `key=value`, the value read as TOML (bare words as strings).
fn parse_override(text: &str) -> Result<(String, Value), String> {
    let (key, raw) = text
        .split_once('=')
        .ok_or_else(|| "expected key=value".to_string())?;
    let key = key.trim().to_string();
    if key.is_empty() {
        return Err("empty key".into());
    }
    let raw = raw.trim();
    let value = match format!("v = {raw}").parse::<Table>() {
        Ok(mut t) => t.remove("v").expect("parsed key"),
        Err(_) => Value::String(raw.to_string()),
    };
    Ok((key, value))
}

fn set_path(root: &mut Table, key: &str, value: Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    let mut table = root;
    for part in &parts[..parts.len() - 1] {
        let entry = table
            .entry(part.to_string())
            .or_insert_with(|| Value::Table(Table::new()));
        table = entry
            .as_table_mut()
            .ok_or_else(|| format!("`{part}` is not a table"))?;
    }
    let last = parts[parts.len() - 1].to_string();
    // A table value merges into an existing table (one axis can set several keys).
    match (table.get_mut(&last), value) {
        (Some(Value::Table(existing)), Value::Table(new)) => {
            for (k, v) in new {
                existing.insert(k, v);
            }
        }
        (_, value) => {
            table.insert(last, value);
        }
    }
    Ok(())
}

fn flatten(table: &Table) -> BTreeMap<String, Value> {
    fn walk(prefix: &str, t: &Table, out: &mut BTreeMap<String, Value>) {
        for (k, v) in t {
            let key = if prefix.is_empty() {
                k.clone()
            } else {
                format!("{prefix}.{k}")
            };
            match v {
                Value::Table(inner) => walk(&key, inner, out),
                other => {
                    out.insert(key, other.clone());
                }
            }
        }
    }
    let mut out = BTreeMap::new();
    walk("", table, &mut out);
    out
}

/// Readable case-name fragment: `K1.5MPa`, `tait`, `mu0.5`, `dyn`.
fn name_part(key: &str, v: &Value) -> String {
    if let Some(remedy) = remedy_descriptor(key) {
        return remedy_name(remedy, v);
    }
    plain_part(key, v)
}

/// `name_part` of a key that is not a remedy's.
fn plain_part(key: &str, v: &Value) -> String {
    let last = key.rsplit('.').next().unwrap_or(key);
    match (last, v) {
        ("K", Value::Float(_) | Value::Integer(_)) => format!("K{}", si_pascal(as_f64(v))),
        ("viscosity", _) => format!("mu{}", as_f64(v)),
        ("coefficient", Value::Float(_) | Value::Integer(_)) => format!("B{:e}", as_f64(v)),
        ("cell", Value::Float(_)) => format!("h{}cm", 100.0 * as_f64(v)),
        ("no_slip", Value::Array(walls)) if walls.is_empty() => "slip".into(),
        ("no_slip", Value::Array(walls)) => {
            let names: Vec<String> = walls.iter().map(|w| name_part("", w)).collect();
            format!("noslip-{}", names.join("-"))
        }
        ("dt", Value::String(s)) if s == "dynamic" => "dyn".into(),
        // An initial flow by its kind and mode: `tg-m2`, `shear`, `wave-m1`.
        ("flow", Value::Table(t)) => {
            let kind = match t.get("kind").and_then(Value::as_str) {
                Some("taylor_green") => "tg",
                Some("shear_wave") => "shear",
                Some("standing_wave") => "wave",
                Some("grid_seed") => "seed",
                _ => "flow",
            };
            // The grid seed's share tells a halved seed from the full one.
            let kind = match t.get("share") {
                Some(share) => format!("{kind}{}", as_f64(share)),
                None => kind.to_string(),
            };
            match t.get("mode") {
                Some(m) => format!("{kind}-m{}", as_f64(m)),
                None => kind,
            }
        }
        // Bodies that differ by their flows, by those, each after its
        // uniform velocity when it has one (`U1x0_seed-m5`).
        ("body", Value::Array(bodies)) if bodies.iter().all(|b| b.get("flow").is_some()) => {
            let flows: Vec<String> = bodies
                .iter()
                .filter_map(|b| {
                    let flow = plain_part("flow", b.get("flow")?);
                    Some(match b.get("velocity") {
                        Some(u) => format!("{}_{flow}", plain_part("U", u)),
                        None => flow,
                    })
                })
                .collect();
            flows.join("+")
        }
        (_, Value::String(s)) => s.clone(),
        // A table that changes nothing: the axis's reference value.
        (_, Value::Table(t)) if t.is_empty() => "base".into(),
        (_, Value::Boolean(true)) => last.to_string(),
        (_, Value::Boolean(false)) => format!("no_{last}"),
        (_, Value::Table(t)) => t
            .iter()
            .map(|(k, v)| name_part(k, v))
            .collect::<Vec<_>>()
            .join("-"),
        ("gamma", _) => format!("g{}", as_f64(v)),
        // A list of numbers (a box's size): `box0.8x0.6`, no brackets or
        // spaces in a folder name.
        (_, Value::Array(xs))
            if !xs.is_empty() && xs.iter().all(|x| x.is_float() || x.is_integer()) =>
        {
            let parts: Vec<String> = xs.iter().map(|x| as_f64(x).to_string()).collect();
            format!("{last}{}", parts.join("x"))
        }
        (_, other) => format!("{last}{other}"),
    }
}

/// The remedy a key names (`method.j_bar`, or `j_bar` inside a method table).
fn remedy_descriptor(key: &str) -> Option<&'static Descriptor> {
    let last = match key.rsplit_once('.') {
        Some(("method", last)) => last,
        Some(_) => return None,
        None => key,
    };
    DESCRIPTORS.iter().copied().find(|d| d.key == last)
}

/// A remedy's fragment, written as its old flat keys were (so names do not
/// change with the keys): `j_bar1.0-linear`, `shift_time0.02`, `f_reset`;
/// off (`false`) as the old zero or `no_` form.
fn remedy_name(d: &Descriptor, v: &Value) -> String {
    let head = |main: Option<&Value>| match d.main {
        Some((setting, default)) => {
            let value = main.cloned().unwrap_or(Value::Float(default));
            plain_part(d.old_key(setting), &value)
        }
        None => plain_part(d.key, &Value::Boolean(true)),
    };
    match v {
        Value::Boolean(false) => match d.main {
            Some((setting, _)) => plain_part(d.old_key(setting), &Value::Float(0.0)),
            None => plain_part(d.key, &Value::Boolean(false)),
        },
        Value::Table(t) => {
            let main = d.main.and_then(|(setting, _)| t.get(setting));
            let mut parts = vec![head(main)];
            for (k, value) in t {
                if d.main.is_some_and(|(setting, _)| setting == k) {
                    continue;
                }
                parts.push(plain_part(d.old_key(k), value));
            }
            parts.join("-")
        }
        _ => head(None),
    }
}

fn as_f64(v: &Value) -> f64 {
    match v {
        Value::Float(f) => *f,
        Value::Integer(i) => *i as f64,
        _ => f64::NAN,
    }
}

fn si_pascal(p: f64) -> String {
    let (scale, unit) = if p >= 1e9 {
        (1e9, "GPa")
    } else if p >= 1e6 {
        (1e6, "MPa")
    } else if p >= 1e3 {
        (1e3, "kPa")
    } else {
        (1.0, "Pa")
    };
    format!("{}{unit}", (p / scale * 1e6).round() / 1e6)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toml(text: &str) -> Value {
        format!("v = {text}")
            .parse::<Table>()
            .unwrap()
            .remove("v")
            .unwrap()
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
    fn shipped_studies_have_unique_case_names() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../studies");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        assert!(files.len() >= 10, "{files:?}");
        for file in files {
            let study = load(&file, &[]).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            let mut names: Vec<&str> = study.cases.iter().map(|c| c.name.as_str()).collect();
            let n = names.len();
            names.sort_unstable();
            names.dedup();
            assert_eq!(names.len(), n, "{}: repeated case names", file.display());
        }
    }

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
