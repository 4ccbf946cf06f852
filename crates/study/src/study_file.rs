//! Study files: TOML schema, validation with file/key/allowed-range errors,
//! `--set` overrides and matrix expansion into named cases.

use monitor::MonitorConfig;
use solver::{
    Body, DtMode, EosKind, InitialState, JUpdate, Material, Method, Perturb, Scene, SchemeKind,
    ShapeKind, SolverConfig, TransferKind,
};
use std::collections::BTreeMap;
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

/// Output cadence of a case.
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    /// Target number of timeseries rows over the run.
    pub timeseries_rows: u64,
    /// Steps between ring checkpoints (0 = none).
    pub checkpoint_every: u64,
    /// Simulated times at which particle VTK files are written.
    pub vtk_times: Vec<f64>,
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
}

#[derive(Clone, Debug)]
pub struct Study {
    pub file: PathBuf,
    pub cases: Vec<Case>,
}

/// Reads, overrides, expands and validates a study file.
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
        .map_err(|e: toml::de::Error| err("", format!("not valid TOML: {}", e.message())))?;
    for o in overrides {
        let (key, value) = parse_override(o).map_err(|m| err(o, m))?;
        set_path(&mut root, &key, value).map_err(|m| err(&key, m))?;
    }
    let matrix = match root.remove("matrix") {
        None => vec![],
        Some(Value::Table(t)) => t.into_iter().collect::<Vec<_>>(),
        Some(_) => return Err(err("matrix", "must be a table of key = [values]".into())),
    };
    let mut axes = vec![];
    for (key, values) in matrix {
        let Value::Array(values) = values else {
            return Err(err(
                &format!("matrix.{key}"),
                "must be an array of values".into(),
            ));
        };
        if values.is_empty() {
            return Err(err(
                &format!("matrix.{key}"),
                "needs at least one value".into(),
            ));
        }
        axes.push((key, values));
    }
    let mut cases = vec![];
    let total: usize = axes.iter().map(|(_, v)| v.len()).product();
    for index in 0..total {
        let mut table = root.clone();
        let mut rest = index;
        let mut name_parts = vec![];
        for (key, values) in axes.iter().rev() {
            let v = &values[rest % values.len()];
            rest /= values.len();
            set_path(&mut table, key, v.clone()).map_err(|m| err(&format!("matrix.{key}"), m))?;
            name_parts.push(name_part(key, v));
        }
        name_parts.reverse();
        let mut reader = Reader {
            file: &file,
            table: &table,
        };
        let (solver, output, monitor) = reader.case()?;
        let base = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "case".into());
        let name = if name_parts.is_empty() {
            base
        } else {
            name_parts.join("_")
        };
        let mut params = flatten(&table);
        // Every method key appears in every case, defaults included.
        if let Ok(Value::Table(m)) = Value::try_from(&solver.method) {
            for (k, v) in m {
                params.entry(format!("method.{k}")).or_insert(v);
            }
        }
        cases.push(Case {
            name,
            monitor,
            params,
            table,
            solver,
            output,
        });
    }
    Ok(Study {
        file: path.to_path_buf(),
        cases,
    })
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
    let last = key.rsplit('.').next().unwrap_or(key);
    match (last, v) {
        ("K", Value::Float(_) | Value::Integer(_)) => format!("K{}", si_pascal(as_f64(v))),
        ("viscosity", _) => format!("mu{}", as_f64(v)),
        ("dt", Value::String(s)) if s == "dynamic" => "dyn".into(),
        (_, Value::String(s)) => s.clone(),
        (_, Value::Table(t)) => t
            .iter()
            .map(|(k, v)| name_part(k, v))
            .collect::<Vec<_>>()
            .join("-"),
        ("gamma", _) => format!("g{}", as_f64(v)),
        (_, other) => format!("{last}{other}"),
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

/// Walks one case's table, consuming known keys and rejecting the rest.
struct Reader<'a> {
    file: &'a str,
    table: &'a Table,
}

impl Reader<'_> {
    fn err(&self, key: &str, message: impl Into<String>) -> StudyError {
        StudyError {
            file: self.file.to_string(),
            key: key.to_string(),
            message: message.into(),
        }
    }

    fn section<'t>(
        &self,
        parent: &'t Table,
        name: &str,
        path: &str,
    ) -> Result<Option<&'t Table>, StudyError> {
        match parent.get(name) {
            None => Ok(None),
            Some(Value::Table(t)) => Ok(Some(t)),
            Some(_) => Err(self.err(path, "must be a table")),
        }
    }

    fn known(&self, t: &Table, path: &str, allowed: &[&str]) -> Result<(), StudyError> {
        for k in t.keys() {
            if !allowed.contains(&k.as_str()) {
                let key = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                return Err(self.err(
                    &key,
                    format!("unknown key (allowed: {})", allowed.join(", ")),
                ));
            }
        }
        Ok(())
    }

    fn float(
        &self,
        t: &Table,
        path: &str,
        key: &str,
        default: Option<f64>,
        lo: f64,
        hi: f64,
    ) -> Result<f64, StudyError> {
        let full = format!("{path}.{key}");
        let v = match t.get(key) {
            None => default.ok_or_else(|| self.err(&full, "is required"))?,
            Some(Value::Float(f)) => *f,
            Some(Value::Integer(i)) => *i as f64,
            Some(other) => {
                return Err(self.err(&full, format!("must be a number, got {other}")));
            }
        };
        if !(v.is_finite() && v >= lo && v <= hi) {
            return Err(self.err(
                &full,
                format!("{v} is out of range (allowed {lo} ..= {hi})"),
            ));
        }
        Ok(v)
    }

    fn int(
        &self,
        t: &Table,
        path: &str,
        key: &str,
        default: i64,
        lo: i64,
        hi: i64,
    ) -> Result<i64, StudyError> {
        let full = format!("{path}.{key}");
        let v = match t.get(key) {
            None => default,
            Some(Value::Integer(i)) => *i,
            Some(other) => return Err(self.err(&full, format!("must be an integer, got {other}"))),
        };
        if v < lo || v > hi {
            return Err(self.err(
                &full,
                format!("{v} is out of range (allowed {lo} ..= {hi})"),
            ));
        }
        Ok(v)
    }

    fn choice<T: Copy>(
        &self,
        t: &Table,
        path: &str,
        key: &str,
        default: T,
        options: &[(&str, T)],
    ) -> Result<T, StudyError> {
        let full = format!("{path}.{key}");
        let names: Vec<String> = options.iter().map(|(n, _)| format!("\"{n}\"")).collect();
        match t.get(key) {
            None => Ok(default),
            Some(Value::String(s)) => options
                .iter()
                .find(|(n, _)| n == s)
                .map(|(_, v)| *v)
                .ok_or_else(|| {
                    self.err(
                        &full,
                        format!("\"{s}\" is not allowed (allowed: {})", names.join(" | ")),
                    )
                }),
            Some(other) => Err(self.err(
                &full,
                format!(
                    "must be a string, got {other} (allowed: {})",
                    names.join(" | ")
                ),
            )),
        }
    }

    fn floats<const N: usize>(
        &self,
        t: &Table,
        path: &str,
        key: &str,
        default: Option<[f64; N]>,
    ) -> Result<[f64; N], StudyError> {
        let full = format!("{path}.{key}");
        let Some(v) = t.get(key) else {
            return default.ok_or_else(|| self.err(&full, "is required"));
        };
        let bad = || self.err(&full, format!("must be an array of {N} numbers"));
        let arr = v.as_array().ok_or_else(bad)?;
        if arr.len() != N {
            return Err(bad());
        }
        let mut out = [0.0; N];
        for (o, x) in out.iter_mut().zip(arr) {
            *o = match x {
                Value::Float(f) if f.is_finite() => *f,
                Value::Integer(i) => *i as f64,
                _ => return Err(bad()),
            };
        }
        Ok(out)
    }

    fn case(&mut self) -> Result<(SolverConfig, Output, MonitorConfig), StudyError> {
        let root = self.table;
        self.known(
            root,
            "",
            &[
                "scene",
                "materials",
                "method",
                "monitor",
                "output",
                "perturb",
                "name",
                "description",
            ],
        )?;
        let materials_t = self
            .section(root, "materials", "materials")?
            .ok_or_else(|| {
                self.err(
                    "materials",
                    "at least one [materials.NAME] table is required",
                )
            })?;
        let mut names = vec![];
        let mut materials = vec![];
        for (name, v) in materials_t {
            let path = format!("materials.{name}");
            let t = v
                .as_table()
                .ok_or_else(|| self.err(&path, "must be a table"))?;
            names.push(name.clone());
            materials.push(self.material(t, &path)?);
        }
        let scene_t = self
            .section(root, "scene", "scene")?
            .ok_or_else(|| self.err("scene", "the [scene] table is required"))?;
        let scene = self.scene(scene_t, &names, materials)?;
        let method_t = self
            .section(root, "method", "method")?
            .cloned()
            .unwrap_or_default();
        let method = self.method(&method_t)?;
        let monitor = match self.section(root, "monitor", "monitor")? {
            Some(t) => self.monitor(t)?,
            None => MonitorConfig::default(),
        };
        let output_t = self
            .section(root, "output", "output")?
            .cloned()
            .unwrap_or_default();
        let output = self.output(&output_t, scene.t_end)?;
        let perturb = self.perturbations(root.get("perturb"))?;
        let cfg = SolverConfig {
            scene,
            method,
            perturb,
        };
        cfg.validate().map_err(|e| self.err(&e.key, e.message))?;
        Ok((cfg, output, monitor))
    }

    /// Every `[monitor]` key is a non-negative number named as in `MonitorConfig`.
    fn monitor(&self, t: &Table) -> Result<MonitorConfig, StudyError> {
        let defaults = Value::try_from(MonitorConfig::default()).expect("config serialises");
        let defaults = defaults.as_table().expect("a table");
        let allowed: Vec<&str> = defaults.keys().map(|k| k.as_str()).collect();
        self.known(t, "monitor", &allowed)?;
        let mut merged = defaults.clone();
        for k in t.keys() {
            let integer = defaults[k].is_integer();
            let value = self.float(t, "monitor", k, None, 0.0, 1e12)?;
            if integer && value.fract() != 0.0 {
                return Err(self.err(
                    &format!("monitor.{k}"),
                    format!("{value} must be a whole number"),
                ));
            }
            merged.insert(
                k.clone(),
                if integer {
                    Value::Integer(value as i64)
                } else {
                    Value::Float(value)
                },
            );
        }
        Value::Table(merged)
            .try_into()
            .map_err(|e: toml::de::Error| self.err("monitor", e.message().to_string()))
    }

    fn material(&self, t: &Table, path: &str) -> Result<Material, StudyError> {
        self.known(
            t,
            path,
            &[
                "rho0",
                "eos",
                "K",
                "gamma",
                "viscosity",
                "j_res",
                "pressure_floor",
            ],
        )?;
        let floor = match t.get("pressure_floor") {
            None => None,
            Some(_) => Some(self.float(t, path, "pressure_floor", None, -1e12, 1e12)?),
        };
        Ok(Material {
            rho0: self.float(t, path, "rho0", Some(1000.0), 1e-6, 1e6)?,
            eos: self.choice(
                t,
                path,
                "eos",
                EosKind::Power,
                &[
                    ("power", EosKind::Power),
                    ("tait", EosKind::Tait),
                    ("linear", EosKind::Linear),
                ],
            )?,
            k: self.float(t, path, "K", None, 1e-6, 1e13)?,
            gamma: self.float(t, path, "gamma", Some(7.0), 1.0, 20.0)?,
            viscosity: self.float(t, path, "viscosity", Some(0.0), 0.0, 1e6)?,
            j_res: self.float(t, path, "j_res", Some(1.0), 0.5, 2.0)?,
            pressure_floor: floor,
        })
    }

    fn scene(
        &self,
        t: &Table,
        names: &[String],
        materials: Vec<Material>,
    ) -> Result<Scene, StudyError> {
        let p = "scene";
        self.known(
            t,
            p,
            &[
                "box", "origin", "cell", "ppc", "t_end", "gravity", "initial", "periodic", "body",
            ],
        )?;
        let size = self.floats::<2>(t, p, "box", Some([0.8, 0.6]))?;
        let cell = self.float(t, p, "cell", Some(0.01), 1e-5, 10.0)?;
        for (a, s) in size.iter().enumerate() {
            let n = s / cell;
            if !(*s > 0.0 && (n - n.round()).abs() < 1e-6 && (2.0..=1e5).contains(&n.round())) {
                return Err(self.err(
                    "scene.box",
                    format!(
                        "axis {a}: {s} m is not a whole number (2 ..= 100000) of {cell} m cells"
                    ),
                ));
            }
        }
        let periodic = match t.get("periodic") {
            None => [false, false],
            Some(v) => {
                let arr = v
                    .as_array()
                    .filter(|a| a.len() == 2 && a.iter().all(|x| x.is_bool()));
                let arr = arr.ok_or_else(|| self.err("scene.periodic", "must be [bool, bool]"))?;
                [
                    arr[0].as_bool() == Some(true),
                    arr[1].as_bool() == Some(true),
                ]
            }
        };
        let mut bodies = vec![];
        let body_list = match t.get("body") {
            None => return Err(self.err("scene.body", "at least one [[scene.body]] is required")),
            Some(Value::Array(a)) => a,
            Some(_) => {
                return Err(self.err("scene.body", "must be an array of tables [[scene.body]]"))
            }
        };
        for (i, b) in body_list.iter().enumerate() {
            let path = format!("scene.body[{i}]");
            let bt = b
                .as_table()
                .ok_or_else(|| self.err(&path, "must be a table"))?;
            self.known(bt, &path, &["rect", "material", "velocity"])?;
            let rect = self.floats::<4>(bt, &path, "rect", None)?;
            let material = match bt.get("material") {
                None if names.len() == 1 => 0,
                None => return Err(self.err(&format!("{path}.material"), "is required")),
                Some(Value::String(s)) => names.iter().position(|n| n == s).ok_or_else(|| {
                    self.err(
                        &format!("{path}.material"),
                        format!("unknown material \"{s}\" (defined: {})", names.join(", ")),
                    )
                })?,
                Some(_) => {
                    return Err(self.err(&format!("{path}.material"), "must be a material name"))
                }
            };
            let velocity = self.floats::<2>(bt, &path, "velocity", Some([0.0, 0.0]))?;
            bodies.push(Body {
                rect,
                material,
                velocity,
            });
        }
        Ok(Scene {
            origin: self.floats::<2>(t, p, "origin", Some([0.0, 0.0]))?,
            size,
            cell,
            ppc: self.int(t, p, "ppc", 2, 1, 8)? as usize,
            t_end: self.float(t, p, "t_end", Some(5.0), 1e-9, 1e4)?,
            gravity: self.float(t, p, "gravity", Some(9.81), 0.0, 1e4)?,
            initial: self.choice(
                t,
                p,
                "initial",
                InitialState::ZeroStress,
                &[
                    ("zero_stress", InitialState::ZeroStress),
                    ("hydrostatic", InitialState::Hydrostatic),
                ],
            )?,
            periodic,
            bodies,
            materials,
        })
    }

    fn method(&self, t: &Table) -> Result<Method, StudyError> {
        let p = "method";
        self.known(
            t,
            p,
            &[
                "shape",
                "transfer",
                "flip_alpha",
                "scheme",
                "cfl",
                "dt",
                "j_update",
                "dt_value",
            ],
        )?;
        let dt_value = match t.get("dt_value") {
            None => None,
            Some(_) => Some(self.float(t, p, "dt_value", None, 1e-12, 1.0)?),
        };
        Ok(Method {
            shape: self.choice(
                t,
                p,
                "shape",
                ShapeKind::Linear,
                &[
                    ("linear", ShapeKind::Linear),
                    ("gimp", ShapeKind::Gimp),
                    ("bspline2", ShapeKind::Bspline2),
                    ("bspline3", ShapeKind::Bspline3),
                ],
            )?,
            transfer: self.choice(
                t,
                p,
                "transfer",
                TransferKind::Flip,
                &[
                    ("pic", TransferKind::Pic),
                    ("flip", TransferKind::Flip),
                    ("apic", TransferKind::Apic),
                ],
            )?,
            flip_alpha: self.float(t, p, "flip_alpha", Some(1.0), 0.0, 1.0)?,
            scheme: self.choice(
                t,
                p,
                "scheme",
                SchemeKind::Usf,
                &[
                    ("usf", SchemeKind::Usf),
                    ("usl", SchemeKind::Usl),
                    ("musl", SchemeKind::Musl),
                ],
            )?,
            cfl: self.float(t, p, "cfl", Some(0.2), 1e-4, 1.0)?,
            dt: self.choice(
                t,
                p,
                "dt",
                DtMode::Fixed,
                &[("fixed", DtMode::Fixed), ("dynamic", DtMode::Dynamic)],
            )?,
            dt_override: dt_value,
            j_update: self.choice(
                t,
                p,
                "j_update",
                JUpdate::Det,
                &[("det", JUpdate::Det), ("exp", JUpdate::Exp)],
            )?,
        })
    }

    fn output(&self, t: &Table, t_end: f64) -> Result<Output, StudyError> {
        let p = "output";
        self.known(t, p, &["timeseries_rows", "checkpoint_every", "vtk_times"])?;
        let vtk_times = match t.get("vtk_times") {
            None => vec![],
            Some(Value::Array(a)) => {
                let mut out = vec![];
                for x in a {
                    let v = match x {
                        Value::Float(f) => *f,
                        Value::Integer(i) => *i as f64,
                        _ => {
                            return Err(
                                self.err("output.vtk_times", "must be an array of times (s)")
                            )
                        }
                    };
                    if !(v >= 0.0 && v.is_finite()) {
                        return Err(self.err(
                            "output.vtk_times",
                            format!("{v} is out of range (allowed finite times >= 0 s)"),
                        ));
                    }
                    // Times past t_end are kept in the file but never reached.
                    if v <= t_end {
                        out.push(v);
                    }
                }
                out
            }
            Some(_) => return Err(self.err("output.vtk_times", "must be an array of times (s)")),
        };
        Ok(Output {
            timeseries_rows: self.int(t, p, "timeseries_rows", 1000, 1, 10_000_000)? as u64,
            checkpoint_every: self.int(t, p, "checkpoint_every", 20_000, 0, i64::MAX)? as u64,
            vtk_times,
        })
    }

    fn perturbations(&self, v: Option<&Value>) -> Result<Vec<Perturb>, StudyError> {
        let Some(v) = v else { return Ok(vec![]) };
        let arr = v
            .as_array()
            .ok_or_else(|| self.err("perturb", "must be an array of tables [[perturb]]"))?;
        let mut out = vec![];
        for (i, e) in arr.iter().enumerate() {
            let path = format!("perturb[{i}]");
            let t = e
                .as_table()
                .ok_or_else(|| self.err(&path, "must be a table"))?;
            self.known(t, &path, &["step", "region", "dv"])?;
            let region = self.floats::<4>(t, &path, "region", None)?;
            if !(region[0] < region[2] && region[1] < region[3]) {
                return Err(self.err(&format!("{path}.region"), "needs x0 < x1 and y0 < y1"));
            }
            out.push(Perturb {
                step: match t.get("step") {
                    None => return Err(self.err(&format!("{path}.step"), "is required")),
                    Some(_) => self.int(t, &path, "step", 1, 1, i64::MAX)? as u64,
                },
                region,
                dv: self.floats::<2>(t, &path, "dv", None)?,
            });
        }
        Ok(out)
    }
}
