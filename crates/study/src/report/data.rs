//! What the report pages read, shared by every section: parquet tables and
//! their columns, the matrix's rows (each case's summary.json with the
//! values of the parameters that vary) and the spread of a set of values.
//! A leaf: it imports no other report module but the plots' number
//! format, so the report modules form a DAG (report -> case / matrix ->
//! the matrix page's sections -> data).

use crate::report::plot::{short, Res};
pub use monitor::stats::{median, spread};
use monitor::Cause;
use polars::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use study::output::summary::{Status, Summary, SCHEMA_VERSION};
use study::study_file::ENSEMBLE_KEYS;

pub fn read_parquet(path: &Path) -> Res<DataFrame> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    ParquetReader::new(file)
        .finish()
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// A numeric column (nulls as NaN).
pub fn f64_column(df: &DataFrame, name: &str) -> Option<Vec<f64>> {
    let c = df.column(name).ok()?.cast(&DataType::Float64).ok()?;
    Some(
        c.f64()
            .ok()?
            .into_iter()
            .map(|v| v.unwrap_or(f64::NAN))
            .collect(),
    )
}

/// Any column as text (nulls as "").
pub fn text_column(df: &DataFrame, name: &str) -> Option<Vec<String>> {
    let c = df.column(name).ok()?;
    Some(
        (0..c.len())
            .map(|i| match c.get(i) {
                // A one-row column reads back as an owned string, which
                // Display would quote.
                Ok(AnyValue::String(s)) => s.to_string(),
                Ok(AnyValue::StringOwned(s)) => s.to_string(),
                Ok(AnyValue::Null) => String::new(),
                Ok(AnyValue::Float64(f)) => short(f),
                Ok(other) => other.to_string(),
                Err(_) => String::new(),
            })
            .collect(),
    )
}

/// One case of the matrix, with the values of the parameters that vary.
pub struct Row {
    pub summary: Summary,
    pub dir: PathBuf,
    /// Values of `Matrix::axes`, as text.
    pub params: Vec<String>,
    /// Relative link to the case's page, when it rendered.
    pub link: Option<String>,
}

/// The outcome heatmap's classes, best to worst: how a run ended when it
/// never kicked, else the cause of its first kick (docs/physics.md 4b).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    NoKickSurvived,
    NoKickBlewUp,
    InjectionFirst,
    InversionFirst,
    AnomalyFirst,
    Failed,
}

impl Class {
    /// Every class, best to worst.
    pub const ALL: [Class; 6] = [
        Class::NoKickSurvived,
        Class::NoKickBlewUp,
        Class::InjectionFirst,
        Class::InversionFirst,
        Class::AnomalyFirst,
        Class::Failed,
    ];
}

impl Row {
    pub fn case(&self) -> &str {
        &self.summary.case
    }

    pub fn status(&self) -> Status {
        self.summary.status
    }

    pub fn t_end(&self) -> f64 {
        self.summary.t_end
    }

    pub fn nan(v: Option<f64>) -> f64 {
        v.unwrap_or(f64::NAN)
    }

    pub fn t_first_kick(&self) -> f64 {
        Row::nan(self.summary.metrics.t_first_kick)
    }

    pub fn hydro_late(&self) -> f64 {
        Row::nan(self.summary.metrics.figure("hydro_rel_rms_late"))
    }

    /// Late departure of a completed run, or over the second before a blow-up.
    pub fn hydro_late_or_pre_failure(&self) -> f64 {
        let m = &self.summary.metrics;
        Row::nan(
            m.figure("hydro_rel_rms_late")
                .or(m.figure("hydro_rel_rms_pre_failure")),
        )
    }

    /// Completed after at least one kick.
    pub fn completed_after_a_kick(&self) -> bool {
        self.status() == Status::Completed && self.summary.kicked()
    }

    /// The row's class in the case table (the page's style): the status
    /// as summary.json spells it, or `kicked` for a run that completed
    /// after a kick.
    pub fn css_class(&self) -> &'static str {
        if self.completed_after_a_kick() {
            "kicked"
        } else {
            self.status().as_str()
        }
    }

    /// The run's outcome class: how it ended, or its first kick's cause.
    pub fn class(&self) -> Class {
        let s = &self.summary;
        if s.status == Status::Failed {
            return Class::Failed;
        }
        let first = s
            .events
            .iter()
            .filter(|e| e.is_kick())
            .min_by(|a, b| a.t.total_cmp(&b.t));
        match first {
            None if s.status == Status::Completed => Class::NoKickSurvived,
            None => Class::NoKickBlewUp,
            Some(e) if e.is_anomaly() => Class::AnomalyFirst,
            Some(e) if e.cause == Cause::Inversion => Class::InversionFirst,
            Some(_) => Class::InjectionFirst,
        }
    }
}

#[cfg(test)]
impl Row {
    pub fn for_test(summary: Summary, params: Vec<String>) -> Self {
        Row {
            summary,
            dir: PathBuf::new(),
            params,
            link: None,
        }
    }
}

/// "m" or "m [lo, hi]" over the finite values ("-" when there are none).
pub fn spread_text(values: impl Iterator<Item = f64>, runs: usize, digits: usize) -> String {
    spread(values).map_or("-".into(), |s| with_spread(s, runs, digits))
}

/// "m" for one run, "m [lo, hi]" for several.
pub fn with_spread(s: (f64, f64, f64), runs: usize, digits: usize) -> String {
    if runs <= 1 {
        format!("{:.*}", digits, s.0)
    } else {
        format!(
            "{:.*} [{:.*}, {:.*}]",
            digits, s.0, digits, s.1, digits, s.2
        )
    }
}

/// Numbers compare as numbers, the rest as text.
pub fn by_value(a: &String, b: &String) -> std::cmp::Ordering {
    match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) => x.total_cmp(&y),
        _ => a.cmp(b),
    }
}

fn param_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Number(n) => n.as_f64().map(short).unwrap_or_else(|| n.to_string()),
        other => other.to_string(),
    }
}

/// The default method, as the params of a summary hold it.
fn method_defaults() -> serde_json::Value {
    serde_json::to_value(solver::Method::default()).unwrap_or_default()
}

/// A param as text. A summary written before a method key existed lacks
/// it and ran with its default, so it reads as the default ("" for other
/// keys).
fn param_or_default(
    params: &BTreeMap<String, serde_json::Value>,
    key: &str,
    defaults: &serde_json::Value,
) -> String {
    params
        .get(key)
        .or_else(|| defaults.get(key.strip_prefix("method.")?))
        .map(param_text)
        .unwrap_or_default()
}

/// A param as the matrix labels it: a material's `eos` by its own
/// parameters (`labels::eos_label_of_params`: "power gamma=7", "tait
/// C=0.0894", "linear"), its `gamma` as "-" unless it is a power law (only
/// the power law has one); any other key as `param_or_default`.
fn axis_text(
    params: &BTreeMap<String, serde_json::Value>,
    key: &str,
    defaults: &serde_json::Value,
) -> String {
    let material = key
        .strip_prefix("materials.")
        .and_then(|k| k.rsplit_once('.'))
        .map(|(name, field)| (format!("materials.{name}"), field));
    let raw = |k: &str| param_or_default(params, k, defaults);
    match material {
        Some((m, "eos")) => {
            let (eos, gamma) = (raw(&format!("{m}.eos")), raw(&format!("{m}.gamma")));
            study::study_file::labels::eos_label_of_params(Some(&eos), Some(&gamma)).unwrap_or(eos)
        }
        Some((m, "gamma")) if !matches!(raw(&format!("{m}.eos")).as_str(), "" | "power") => {
            "-".into()
        }
        _ => raw(key),
    }
}

/// The rows of a matrix, sorted by the varying parameters, and those parameters' keys.
pub struct Matrix {
    pub axes: Vec<ParamKey>,
    pub rows: Vec<Row>,
    /// Cases of other matrices that the report reads for reference (the
    /// yardsticks' folders, `kick report --yardsticks`); not this matrix's.
    pub reference_rows: Vec<Row>,
    /// The case whose method is the Methods table's baseline (`kick report
    /// --baseline`; None: the most common value of each method key).
    pub baseline_case: Option<String>,
    /// Runs of earlier matrices kept as records (`kick report
    /// --behaviour-runs`): only the four-behaviour table reads them.
    pub recorded_runs: Vec<RecordedRun>,
}

/// What the four-behaviour table reads of a run's timeseries, kept so
/// that a run folder need not survive for its run to be scored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BehaviourFigures {
    /// Steps from the kick that began the blow-out to half of the
    /// particles gone (None: no such kick, or half never gone).
    pub blow_out_steps: Option<f64>,
    /// Time at which the run had lost the survival share of its mass, else its end (s).
    pub survived: f64,
    /// Ran to the matrix's t_end without losing that share.
    pub survived_to_end: bool,
    /// Largest cell-means checkerboard index over the bug report's window.
    pub early_checkerboard: Option<f64>,
}

/// One line of a behaviour record (`report/behaviour_runs.jsonl`): the
/// run's summary without its events, and its timeseries' figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecordedRun {
    pub summary: Summary,
    pub figures: BehaviourFigures,
}

/// The runs of a behaviour record, one JSON object a line; errors name
/// the file and the line.
pub fn read_recorded_runs(path: &Path) -> Res<Vec<RecordedRun>> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut runs = vec![];
    // The version first, so that an older record says so rather than
    // naming the field it lacks.
    #[derive(Deserialize)]
    struct Version {
        schema_version: Option<u32>,
    }
    #[derive(Deserialize)]
    struct Versioned {
        summary: Version,
    }
    for (i, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let at = format!("{}: line {}", path.display(), i + 1);
        let version = serde_json::from_str::<Versioned>(line)
            .map_err(|e| format!("{at}: not a recorded run: {e}"))?
            .summary
            .schema_version;
        if version != Some(SCHEMA_VERSION) {
            return Err(format!(
                "{at}: schema_version {} is not {SCHEMA_VERSION} (written by another kick version: run the case again)",
                version.map_or("missing".into(), |v| v.to_string())
            ));
        }
        let run: RecordedRun =
            serde_json::from_str(line).map_err(|e| format!("{at}: not a recorded run: {e}"))?;
        runs.push(run);
    }
    Ok(runs)
}

/// A study parameter's dotted key (`materials.water.K`, `method.j_bar.blend`,
/// `scene.cell`), typed by what it sets.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum ParamKey {
    /// `materials.NAME.FIELD`
    Material { name: String, field: String },
    /// `method.FIELD` (a remedy's setting is dotted: `j_bar.blend`)
    Method(String),
    /// `scene.FIELD`
    Scene(String),
    /// Any other key (`drag.update`, ...), as written.
    Other(String),
}

impl ParamKey {
    pub fn parse(key: &str) -> Self {
        if let Some((name, field)) = key
            .strip_prefix("materials.")
            .and_then(|k| k.split_once('.'))
        {
            return ParamKey::Material {
                name: name.into(),
                field: field.into(),
            };
        }
        if let Some(field) = key.strip_prefix("method.") {
            return ParamKey::Method(field.into());
        }
        if let Some(field) = key.strip_prefix("scene.") {
            return ParamKey::Scene(field.into());
        }
        ParamKey::Other(key.into())
    }

    /// A material's bulk modulus K.
    pub fn is_bulk_modulus(&self) -> bool {
        matches!(self, ParamKey::Material { field, .. } if field == "K")
    }

    /// A material's viscosity.
    pub fn is_viscosity(&self) -> bool {
        matches!(self, ParamKey::Material { field, .. } if field == "viscosity")
    }

    /// The cell size h.
    pub fn is_cell_size(&self) -> bool {
        matches!(self, ParamKey::Scene(f) if f == "cell")
    }

    /// The key without its section (`K`, `transfer`, `cell`).
    pub fn field(&self) -> &str {
        match self {
            ParamKey::Material { field, .. } => field,
            ParamKey::Method(f) | ParamKey::Scene(f) | ParamKey::Other(f) => f,
        }
    }
}

impl std::fmt::Display for ParamKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamKey::Material { name, field } => write!(f, "materials.{name}.{field}"),
            ParamKey::Method(k) => write!(f, "method.{k}"),
            ParamKey::Scene(k) => write!(f, "scene.{k}"),
            ParamKey::Other(k) => f.write_str(k),
        }
    }
}

impl Matrix {
    /// The case names of the matrix in `dir` (summary.parquet's `case`).
    pub fn case_names(dir: &Path) -> Res<Vec<String>> {
        let df = read_parquet(&dir.join("summary.parquet"))?;
        text_column(&df, "case").ok_or_else(|| "summary.parquet lacks case".into())
    }

    /// Every case of the matrix folder `dir` (found through
    /// summary.parquet's `case_dir`), sorted by the parameters that vary.
    pub fn read(dir: &Path) -> Res<Self> {
        let df = read_parquet(&dir.join("summary.parquet"))?;
        let dirs = text_column(&df, "case_dir").ok_or("summary.parquet lacks case_dir")?;
        let summaries: Vec<(PathBuf, Summary)> = dirs
            .iter()
            .map(|d| {
                let case_dir = dir.join(d);
                Summary::read(&case_dir).map(|s| (case_dir, s))
            })
            .collect::<Res<_>>()?;
        Ok(Matrix::of(summaries))
    }

    /// The matrix of these cases (each with its folder), sorted by the
    /// parameters that vary between them.
    pub fn of(summaries: Vec<(PathBuf, Summary)>) -> Self {
        let defaults = method_defaults();
        let text = |s: &Summary, k: &String| axis_text(&s.params, k, &defaults);
        let keys = Matrix::axes_of(&summaries, &text);
        let mut rows: Vec<Row> = summaries
            .into_iter()
            .map(|(dir, summary)| Row {
                params: keys.iter().map(|k| text(&summary, k)).collect(),
                summary,
                dir,
                link: None,
            })
            .collect();
        rows.sort_by(|a, b| {
            a.params
                .iter()
                .zip(&b.params)
                .map(|(x, y)| by_value(x, y))
                .find(|o| o.is_ne())
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        let axes = keys.iter().map(|k| ParamKey::parse(k)).collect();
        Matrix {
            axes,
            rows,
            reference_rows: vec![],
            baseline_case: None,
            recorded_runs: vec![],
        }
    }

    /// The keys whose text (`text`) differs between the summaries, but the
    /// ensemble's and a material's `gamma` when its `eos` varies too.
    fn axes_of(
        summaries: &[(PathBuf, Summary)],
        text: &dyn Fn(&Summary, &String) -> String,
    ) -> Vec<String> {
        // Ensemble members differ only in their seed: one case, several runs.
        let keys: BTreeSet<&String> = summaries
            .iter()
            .flat_map(|(_, s)| s.params.keys())
            .filter(|k| !ENSEMBLE_KEYS.contains(&k.as_str()))
            .collect();
        let varying: Vec<String> = keys
            .into_iter()
            .filter(|k| {
                summaries
                    .iter()
                    .map(|(_, s)| text(s, k))
                    .collect::<BTreeSet<_>>()
                    .len()
                    > 1
            })
            .cloned()
            .collect();
        // A material's `eos` axis is labelled with its gamma (power law
        // only): its `gamma` axis would repeat it.
        varying
            .iter()
            .filter(|k| {
                !k.strip_suffix(".gamma")
                    .is_some_and(|m| varying.contains(&format!("{m}.eos")))
            })
            .cloned()
            .collect()
    }

    /// The first axis whose key `is` (e.g. `ParamKey::is_bulk_modulus`).
    pub fn axis(&self, is: impl Fn(&ParamKey) -> bool) -> Option<usize> {
        self.axes.iter().position(is)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_method_key_missing_from_an_older_summary_reads_as_its_default() {
        let defaults = method_defaults();
        let mut params = BTreeMap::new();
        params.insert("method.cfl".to_string(), serde_json::json!(0.4));
        let text = |k: &str| param_or_default(&params, k, &defaults);
        assert_eq!(text("method.cfl"), param_text(&serde_json::json!(0.4)));
        assert_eq!(text("method.xpic_order"), param_text(&serde_json::json!(2)));
        // A remedy missing from a summary was off: no setting to show.
        assert_eq!(text("method.shifting.time"), "");
        assert_eq!(text("method.transfer"), "flip");
        assert_eq!(text("materials.water.K"), "");
        assert_eq!(text("method.no_such_key"), "");
    }

    /// A Tait or linear material never reads "gamma 7": its `eos` axis
    /// carries its own parameter and its `gamma` does not apply.
    #[test]
    fn materials_are_labelled_by_their_own_eos_parameters() {
        let defaults = method_defaults();
        let params = |eos: Option<&str>, gamma: f64| {
            let mut p = BTreeMap::new();
            if let Some(eos) = eos {
                p.insert("materials.water.eos".to_string(), serde_json::json!(eos));
            }
            p.insert(
                "materials.water.gamma".to_string(),
                serde_json::json!(gamma),
            );
            p.insert("materials.water.K".to_string(), serde_json::json!(1.5e4));
            p
        };
        let text = |p: &BTreeMap<String, serde_json::Value>, k: &str| axis_text(p, k, &defaults);
        let tait = params(Some("tait"), 7.0);
        assert_eq!(text(&tait, "materials.water.eos"), "tait C=0.0894");
        assert_eq!(text(&tait, "materials.water.gamma"), "-");
        let power = params(Some("power"), 4.0);
        assert_eq!(text(&power, "materials.water.eos"), "power gamma=4");
        assert_eq!(text(&power, "materials.water.gamma"), "4");
        let default = params(None, 7.0);
        assert_eq!(text(&default, "materials.water.eos"), "power gamma=7");
        let linear = params(Some("linear"), 7.0);
        assert_eq!(text(&linear, "materials.water.eos"), "linear");
        assert_eq!(text(&linear, "materials.water.K"), "1.5e4");
    }

    fn run(status: Status, first_kick: Option<Cause>) -> Row {
        use study::output::summary::{sample_event, Metrics, SCHEMA_VERSION};
        let events: Vec<monitor::Event> = first_kick
            .into_iter()
            .map(|cause| {
                let mut e = sample_event();
                e.cause = cause;
                e
            })
            .collect();
        let kick = events.iter().find(|e| e.is_kick()).map(|e| e.t);
        let summary = Summary {
            schema_version: SCHEMA_VERSION,
            case: "c".into(),
            params: Default::default(),
            status,
            reason: String::new(),
            steps: 10,
            t_end: 1.0,
            wall_s: 1.0,
            particles: 10,
            particle_steps_per_s: 1.0,
            final_state_hash: "0".into(),
            events,
            metrics: Metrics {
                t_first_kick: kick,
                ..Metrics::default()
            },
            phases: vec![],
        };
        Row::for_test(summary, vec![])
    }

    /// The case table's row class is the status as summary.json spells
    /// it, or `kicked`; the heatmap's class is how a run ended or what
    /// kicked it first.
    #[test]
    fn a_row_is_classed_by_its_status_and_first_kick() {
        let cases = [
            (Status::Completed, None, "completed", Class::NoKickSurvived),
            (
                Status::Completed,
                Some(Cause::Injection),
                "kicked",
                Class::InjectionFirst,
            ),
            // An impact is no kick.
            (
                Status::Completed,
                Some(Cause::Impact),
                "completed",
                Class::NoKickSurvived,
            ),
            (Status::BlewUp, None, "blew_up", Class::NoKickBlewUp),
            (
                Status::BlewUp,
                Some(Cause::Inversion),
                "blew_up",
                Class::InversionFirst,
            ),
            (Status::Failed, None, "failed", Class::Failed),
        ];
        for (status, cause, css, class) in cases {
            let r = run(status, cause);
            assert_eq!(
                (r.css_class(), r.class()),
                (css, class),
                "{status:?} {cause:?}"
            );
        }
    }

    #[test]
    fn the_spread_is_the_median_and_range_of_the_finite_values() {
        let v = [3.0, f64::NAN, 1.0, 2.0, 10.0];
        assert_eq!(spread(v.iter().copied()), Some((2.5, 1.0, 10.0)));
        assert_eq!(median(&[f64::NAN]), None);
        assert_eq!(spread_text(v.iter().copied(), 4, 1), "2.5 [1.0, 10.0]");
        assert_eq!(spread_text(v.iter().copied(), 1, 2), "2.50");
        assert_eq!(spread_text(std::iter::empty(), 1, 2), "-");
    }
}
