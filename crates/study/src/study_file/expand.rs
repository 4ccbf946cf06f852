//! Case expansion: the matrix axes (and the extra blocks that replace
//! some) and the ensemble members, each case deserialised and named.

use super::*;

/// The cases of one product of `axes` over `root`, in axis order (the
/// last axis varies fastest), each ensemble member a case of its own.
pub(super) fn expand(
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
                // Members K of a base seed s: seeds s + K. (The user's
                // table, read raw: the typed read comes per case.)
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
    // The user's tables, read raw: the keys a formulation's entry sets
    // exist only there, before the typed read.
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
pub(super) fn extra_blocks(matrix: &mut Option<Value>) -> Result<Vec<Table>, KeyError> {
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
pub(super) fn replace_axes(axes: &[Axis], block: Table, key: &str) -> Result<Vec<Axis>, KeyError> {
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
pub(super) fn ensemble_size(matrix: &mut Option<Value>) -> Result<Option<u64>, KeyError> {
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

/// The `[matrix]` table as axes, in file order.
pub(super) fn matrix_axes(matrix: Option<Value>) -> Result<Vec<Axis>, KeyError> {
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
pub(super) fn case(name: String, table: Table) -> Result<Case, KeyError> {
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
