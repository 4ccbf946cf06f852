//! The per-case report page: the verdict (status, kicks by cause with their
//! times and places), the first kick before, at and after, the metrics that
//! apply, events, time series, surge front, particle maps, pressure against
//! depth, and each other event before, at and after (with an animation).

pub mod verdict;

use crate::report::data::{f64_column, read_parquet};
use crate::report::html::{escape, Cell, Page};
use crate::report::plot::case::{
    animate, FrontFigure, MapsFigure, Marker, Outline, PressureDepthFigure, Series,
    TimeseriesFigure,
};
use crate::report::plot::{err, render, short, Res};
use monitor::{Cause, Event, EventKind};
use plotters::style::RGBColor;
use solver::Scene;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use study::output::files::write_atomic;
use study::output::metrics::martin_moyce;
use study::output::summary::Summary;
use study::output::vtu::particle_files;
use study::output::vtu::Snapshot;
use study::replay::explain::record::ExplainedHead;
use study::run::probes::surge_front::front_wall_z;
use study::study_file;

/// What the page shows, read from the case folder.
struct CaseInputs {
    dir: PathBuf,
    out: PathBuf,
    summary: Summary,
    scene: Scene,
    series: Series,
}

impl CaseInputs {
    fn read(dir: &Path) -> Res<Self> {
        let summary = Summary::read(dir)?;
        let study = study_file::load(&dir.join("case.toml"), &[]).map_err(|e| e.to_string())?;
        let scene = study.cases[0].solver.scene.clone();
        let df = read_parquet(&dir.join("timeseries.parquet"))?;
        let t = f64_column(&df, "t").ok_or("timeseries lacks t")?;
        let columns = df
            .get_column_names()
            .iter()
            .filter_map(|n| f64_column(&df, n).map(|v| (n.to_string(), v)))
            .collect();
        Ok(CaseInputs {
            dir: dir.to_path_buf(),
            out: dir.join("report"),
            summary,
            scene,
            series: Series { t, columns },
        })
    }

    fn name(&self) -> &str {
        &self.summary.case
    }

    fn gravity(&self) -> f64 {
        if self.scene.gravity > 0.0 {
            self.scene.gravity
        } else {
            9.81
        }
    }

    fn bbox(&self) -> [f64; 4] {
        let s = &self.scene;
        [
            s.origin[0],
            s.origin[1],
            s.origin[0] + s.size[0],
            s.origin[1] + s.size[1],
        ]
    }
}

fn load_snapshot(path: &Path) -> Res<Snapshot> {
    study::output::vtu::read_file(path)
}

/// The per-case page; returns its path. It opens with the verdict (how the
/// run ended, its kicks by cause with times and places), then the picture
/// of the first kick, then the metrics that apply to the scene.
pub fn case_report(dir: &Path) -> Res<PathBuf> {
    let c = CaseInputs::read(dir)?;
    let mut page = Page::default();
    verdict_section(&c, &mut page);
    let events = &c.summary.events;
    let first_kick = verdict::kicks(events).first().copied();
    if let Some(e) = first_kick {
        event_section(&c, e, "First kick: ", &mut page)?;
    }
    metrics_section(&c, &mut page);
    events_section(&c, &mut page);
    explained_section(&c, &mut page);
    timeseries_section(&c, &mut page)?;
    particles_section(&c, &mut page)?;
    for e in events
        .iter()
        .filter(|e| !first_kick.is_some_and(|f| std::ptr::eq(*e, f)))
    {
        event_section(&c, e, "", &mut page)?;
    }
    let index = c.out.join("index.html");
    write_atomic(
        &index,
        page.finish(&format!("kick report: {}", c.name()))
            .as_bytes(),
    )
    .map_err(err)?;
    Ok(index)
}

/// Status, kicks by cause with their times and places, materials, cost.
fn verdict_section(c: &CaseInputs, page: &mut Page) {
    let s = &c.summary;
    page.begin_section("verdict");
    page.h2("Verdict");
    page.p(&verdict::status_sentence(s));
    page.p(&verdict::kicks_sentence(&s.events, &c.scene));
    causes_table(c, page);
    let materials: Vec<String> = c
        .scene
        .materials
        .iter()
        .map(|m| escape(&study::study_file::labels::named_material_label(m)))
        .collect();
    page.p(&format!(
        "Materials: {}. {} particles; wall {:.1} s, {:.2} M particle-steps/s.",
        materials.join("; "),
        s.particles,
        s.wall_s,
        s.particle_steps_per_s / 1e6
    ));
    page.end_section();
}

/// Events by cause, kicks first: how many, and the times and places of the
/// first three.
fn causes_table(c: &CaseInputs, page: &mut Page) {
    const SHOWN: usize = 3;
    let events = &c.summary.events;
    let rows: Vec<(String, Vec<Cell>)> = verdict::CAUSE_ORDER
        .iter()
        .filter_map(|&cause| {
            let mut of: Vec<&Event> = events.iter().filter(|e| e.cause == cause).collect();
            let first = *of.first()?;
            of.sort_by(|a, b| a.t.total_cmp(&b.t));
            let mut places: Vec<String> = of
                .iter()
                .take(SHOWN)
                .map(|e| {
                    format!(
                        "t = {:.4} s, step {}: {}",
                        e.t,
                        e.first_step,
                        escape(&verdict::place(&e.region, &c.scene))
                    )
                })
                .collect();
            if of.len() > SHOWN {
                places.push(format!("and {} more", of.len() - SHOWN));
            }
            let kind = if first.is_kick() {
                "kick"
            } else {
                "not a kick"
            };
            Some((
                String::new(),
                vec![
                    Cell::Text(format!(
                        "<span style=\"color:{}\">{}</span> ({kind})",
                        cause_css(first),
                        cause.name()
                    )),
                    Cell::Num(of.len().to_string()),
                    Cell::Text(places.join("<br>")),
                ],
            ))
        })
        .collect();
    if rows.is_empty() {
        page.p("No event.");
        return;
    }
    let headers = ["cause", "events", "times and places (first three)"].map(String::from);
    page.table("causes", &headers, &rows);
}

/// The metrics that apply to this scene, with units (`verdict`).
fn metrics_section(c: &CaseInputs, page: &mut Page) {
    page.h2("Metrics");
    let rows: Vec<(String, Vec<Cell>)> = verdict::metric_rows(&c.summary.metrics)
        .into_iter()
        .map(|r| {
            (
                String::new(),
                vec![
                    Cell::Text(escape(r.label)),
                    Cell::Num(r.value),
                    Cell::Text(escape(r.unit)),
                ],
            )
        })
        .collect();
    if rows.is_empty() {
        page.p("No metric is defined for this run.");
        return;
    }
    let headers = ["metric", "value", "unit"].map(String::from);
    page.table("metrics", &headers, &rows);
}

fn events_section(c: &CaseInputs, page: &mut Page) {
    let events = &c.summary.events;
    page.h2("Events");
    if events.is_empty() {
        page.p("No event.");
        return;
    }
    let headers = [
        "id",
        "kind",
        "first step",
        "t (s)",
        "place",
        "particles",
        "peak a/g",
        "jump (m/s)",
        "Courant",
        "quiescent before",
        "previously deformed",
        "cause",
        "hallmark",
        "outcome",
        "Courant before / critical",
        "advection before",
        "energy rise / floor (J/m)",
        "rules",
    ]
    .map(String::from);
    let rows: Vec<(String, Vec<Cell>)> = events
        .iter()
        .map(|e| {
            (
                String::new(),
                vec![
                    Cell::Num(e.id.to_string()),
                    Cell::Text(kind_name(e.kind)),
                    Cell::Num(e.first_step.to_string()),
                    Cell::Num(format!("{:.4}", e.t)),
                    Cell::Text(escape(&verdict::place(&e.region, &c.scene))),
                    Cell::Num(e.n_particles.to_string()),
                    Cell::Num(short(e.peak_accel_g)),
                    Cell::Num(short(e.jump_speed)),
                    Cell::Num(format!("{:.2}", e.courant)),
                    Cell::Num(e.quiescent_before.to_string()),
                    Cell::Num(e.previously_deformed().to_string()),
                    Cell::Text(format!(
                        "<span style=\"color:{}\">{}</span>",
                        cause_css(e),
                        e.cause.name()
                    )),
                    Cell::Num(if e.hallmark() { "yes" } else { "" }.into()),
                    Cell::Text(serde_name(&e.outcome)),
                    Cell::Num(format!(
                        "{:.2} / {:.1}",
                        e.evidence.courant_before, e.evidence.critical_courant
                    )),
                    Cell::Num(format!("{:.3}", e.evidence.advection_before)),
                    Cell::Num(format!(
                        "{} / {}",
                        short(e.energy_injected),
                        short(e.evidence.energy_floor)
                    )),
                    Cell::Text(e.rules.names().join(", ")),
                ],
            )
        })
        .collect();
    page.table("", &headers, &rows);
}

/// The events `kick explain` wrote a folder for (CASE_DIR/explain/event_K):
/// their largest part, leading mechanism and picture, linked.
fn explained_section(c: &CaseInputs, page: &mut Page) {
    let found: Vec<(u32, ExplainedHead)> = c
        .summary
        .events
        .iter()
        .filter_map(|e| Some((e.id, ExplainedHead::read(&c.dir, e.id)?)))
        .collect();
    if found.is_empty() {
        return;
    }
    page.h2("Explained events (kick explain)");
    for (id, head) in found {
        let folder = format!("../explain/event_{id}");
        let (part, lead) = (&head.largest_part, &head.leading);
        page.p(&format!(
            "Event {id}: largest part {} ({:.3}); leading mechanism {} ({:.3}); {}.",
            escape(&part.part),
            part.share.unwrap_or(f64::NAN),
            escape(&lead.mechanism),
            lead.share.unwrap_or(f64::NAN),
            crate::report::html::link(Some(&format!("{folder}/explain.json")), "explain.json"),
        ));
        page.image(
            &format!("{folder}/explain_cells.png"),
            &format!("event {id}: stencil nodes and contributing particles"),
            "At the onset window's start and at the event's first step: nodes by mass share (red: light), net nodal forces, contributing particles by pressure, the event's ringed",
        );
    }
}

fn serde_name<T: serde::Serialize + std::fmt::Debug>(v: &T) -> String {
    match serde_json::to_value(v) {
        Ok(serde_json::Value::String(s)) => s,
        _ => format!("{v:?}"),
    }
}

fn kind_name(kind: EventKind) -> String {
    serde_name(&kind)
}

/// Events by cause: kicks (injection, inversion, jump) red, time-step
/// instability (cfl) orange, impacts (physics) grey.
fn cause_colour(e: &Event) -> RGBColor {
    match e.cause {
        Cause::Injection | Cause::Inversion | Cause::Jump => RGBColor(200, 30, 30),
        Cause::Cfl => RGBColor(230, 140, 20),
        Cause::Impact => RGBColor(120, 120, 120),
    }
}

fn cause_css(e: &Event) -> String {
    let RGBColor(r, g, b) = cause_colour(e);
    format!("#{r:02x}{g:02x}{b:02x}")
}

fn timeseries_section(c: &CaseInputs, page: &mut Page) -> Res {
    let markers: Vec<Marker> = c
        .summary
        .events
        .iter()
        .map(|e| Marker {
            id: e.id,
            t: e.t,
            colour: cause_colour(e),
            note: if e.hallmark() {
                "*".into()
            } else {
                String::new()
            },
        })
        .collect();
    page.h2("Time series");
    let fig = TimeseriesFigure {
        series: &c.series,
        markers: &markers,
        title: format!(
            "{}: energy, kicks, checkerboard, hydrostatic departure",
            c.name()
        ),
    };
    page.figure(&render(&fig, &c.out, "timeseries")?, "Energy budget, injected energy, max a/g and outlier score, checkerboard index and hydrostatic departure; event lines by cause: kicks (injection, inversion) red, time-step instability (cfl) orange, impacts grey; * marks the hallmark");
    if let (Some(z_wall), Some(ft), Some(fz)) = (
        front_wall_z(&c.scene),
        c.series.column("front_t"),
        c.series.column("front_z"),
    ) {
        let data = martin_moyce();
        let fig = FrontFigure {
            t: ft,
            z: fz,
            data: &data,
            z_wall,
            title: format!("{}: surge front", c.name()),
        };
        page.figure(
            &render(&fig, &c.out, "front")?,
            "Surge front Z(T) against Martin & Moyce (1952)",
        );
    }
    Ok(())
}

/// Particle maps at four of the study's times, and late pressure against depth.
fn particles_section(c: &CaseInputs, page: &mut Page) -> Res {
    let files = particle_files(&c.dir.join("particles"));
    let Some(last_file) = files.last() else {
        return Ok(());
    };
    let pick: BTreeSet<usize> = (0..4).map(|k| k * (files.len() - 1) / 3).collect();
    let snaps: Vec<Snapshot> = pick
        .iter()
        .map(|&k| load_snapshot(&files[k]))
        .collect::<Res<_>>()?;
    let fig = MapsFigure {
        snaps: snaps
            .iter()
            .map(|s| (s, format!("t = {:.3} s", s.t)))
            .collect(),
        bbox: c.bbox(),
        outline: None,
        gravity: c.gravity(),
        title: format!("{}: pressure (top) and a/g (bottom)", c.name()),
    };
    page.h2("Particles");
    page.figure(
        &render(&fig, &c.out, "maps")?,
        "Particles coloured by pressure and by acceleration over g",
    );
    let last = load_snapshot(last_file)?;
    let scene = &c.scene;
    let area: f64 = scene
        .bodies
        .iter()
        .map(|b| (b.rect[2] - b.rect[0]) * (b.rect[3] - b.rect[1]))
        .sum();
    let late = |name: &str| c.summary.metrics.figure(name).map_or("-".into(), short);
    let fig = PressureDepthFigure {
        snap: &last,
        level: scene.origin[1] + area / scene.size[0],
        rho0: scene.materials.first().map_or(1000.0, |m| m.rho0),
        gravity: c.gravity(),
        title: format!(
            "{}, t = {:.2} s: late hydrostatic rel. RMS {} (floor {}, excess {}; {} not explained by the accelerations)",
            c.name(),
            last.t,
            late("hydro_rel_rms_late"),
            late("hydro_floor_late"),
            late("hydro_excess_late"),
            late("hydro_unexplained_rel_rms_late"),
        ),
    };
    page.figure(
        &render(&fig, &c.out, "pressure_depth")?,
        "Pressure against depth at the last snapshot, with the hydrostatic line",
    );
    Ok(())
}

/// One event: before, at and after with its region outlined, and an
/// animation; `note` leads its heading ("First kick: ").
fn event_section(c: &CaseInputs, e: &Event, note: &str, page: &mut Page) -> Res {
    let id = e.id;
    let files = particle_files(&c.dir.join("particles").join(format!("event_{id}")));
    if files.is_empty() {
        return Ok(());
    }
    let frames: Vec<Snapshot> = files.iter().map(|p| load_snapshot(p)).collect::<Res<_>>()?;
    let r = &e.region;
    let outline = Some(Outline {
        x0: r.x_min,
        y0: r.y_min,
        x1: r.x_max,
        y1: r.y_max,
    });
    let at = frames
        .iter()
        .position(|f| f.step == e.first_step)
        .unwrap_or(0);
    let mut chosen = vec![];
    if at > 0 {
        chosen.push((&frames[at - 1], "before"));
    }
    chosen.push((&frames[at], "at"));
    if at + 1 < frames.len() {
        chosen.push((frames.last().expect("non-empty"), "after"));
    }
    let kind = kind_name(e.kind);
    let fig = MapsFigure {
        snaps: chosen
            .iter()
            .map(|(s, w)| (*s, format!("{w}: step {}, t = {:.4} s", s.step, s.t)))
            .collect(),
        bbox: c.bbox(),
        outline,
        gravity: c.gravity(),
        title: format!("{}: {kind} #{id} (region outlined)", c.name()),
    };
    let lead = if note.is_empty() {
        "Event".to_string()
    } else {
        format!("{note}event")
    };
    page.h2(&format!(
        "{lead} {id} ({kind}, {}, step {}, t = {:.4} s)",
        e.cause.name(),
        e.first_step,
        e.t
    ));
    page.figure(
        &render(&fig, &c.out, &format!("event_{id}_maps"))?,
        "Before, at and after the event: pressure (top), a/g (bottom)",
    );
    let gif = format!("event_{id}.gif");
    animate(
        &frames,
        c.bbox(),
        outline,
        &format!("{kind} #{id}"),
        &c.out.join(&gif),
        c.gravity(),
    )?;
    page.image(
        &gif,
        &format!("animation of event {id}"),
        &format!("Animation around event {id} (every 5 steps)"),
    );
    Ok(())
}
