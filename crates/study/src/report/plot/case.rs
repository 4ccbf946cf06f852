//! Per-case figures: time series on a shared time axis with kicks marked,
//! surge front against Martin & Moyce, late pressure against depth, particle
//! maps (pressure and a/g with colour bars) and the animation of a kick.

use crate::report::plot::{
    colour_bar, draw_title, err, fonts, legend, log_label, series_colour, short, titled,
    ColourScale, Figure, LogAxis, Res, SANS,
};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use study::output::vtu::Snapshot;

/// Named columns of a timeseries (NaN = missing).
pub struct Series {
    pub t: Vec<f64>,
    pub columns: Vec<(String, Vec<f64>)>,
}

impl Series {
    /// A column by its name in `output::timeseries::COLUMNS` (None when the
    /// table lacks it: an older table).
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        debug_assert!(
            study::output::timeseries::COLUMNS
                .iter()
                .any(|c| c.name == name),
            "{name} is not a declared timeseries column"
        );
        self.columns
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// A kick marker: id and time.
pub struct Marker {
    pub id: u32,
    pub t: f64,
    /// Line colour (the report colours events by cause).
    pub colour: RGBColor,
    /// Text after the id, e.g. "*" for the hallmark.
    pub note: String,
}

pub struct TimeseriesFigure<'a> {
    pub series: &'a Series,
    pub markers: &'a [Marker],
    pub title: String,
}

struct Panel {
    ylabel: String,
    lines: Vec<(&'static str, Vec<f64>)>,
    log: bool,
}

/// A panel's axis label: its title and the unit its columns declare
/// (`timeseries::COLUMNS`), and "log" on a log axis.
fn axis_label(title: &str, column: &str, log: bool) -> String {
    let unit = study::output::timeseries::column(column).map_or("1", |c| c.unit);
    match (unit, log) {
        ("1", false) => title.to_string(),
        ("1", true) => format!("{title} (log)"),
        (unit, false) => format!("{title} ({unit})"),
        (unit, true) => format!("{title} ({unit}, log)"),
    }
}

fn finite_range(lines: &[(&str, Vec<f64>)], log: bool) -> (f64, f64) {
    let vals = lines
        .iter()
        .flat_map(|(_, v)| v.iter().copied())
        .filter(|x| x.is_finite() && (!log || *x > 0.0));
    let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if !lo.is_finite() {
        // log: log10 of 1e-3..1
        return if log { (-3.0, 0.0) } else { (0.0, 1.0) };
    }
    if log {
        // Whole decades at both ends; LogAxis::new keeps this as it is.
        let lo = lo.max(hi * 1e-9);
        (
            lo.log10().floor(),
            hi.log10().ceil().max(lo.log10().floor() + 1.0),
        )
    } else {
        let pad = ((hi - lo) * 0.05).max(1e-12 + lo.abs() * 1e-6);
        (lo - pad, hi + pad)
    }
}

impl TimeseriesFigure<'_> {
    fn panels(&self) -> Vec<Panel> {
        let s = self.series;
        let col = |n: &str| {
            s.column(n)
                .map(|v| v.to_vec())
                .unwrap_or_else(|| vec![f64::NAN; s.t.len()])
        };
        let rel = |n: &str| {
            let v = col(n);
            let v0 = v.first().copied().unwrap_or(0.0);
            v.iter().map(|x| x - v0).collect::<Vec<_>>()
        };
        vec![
            Panel {
                ylabel: axis_label("energy change", "e_kin", false),
                lines: vec![
                    ("kinetic", col("e_kin")),
                    ("affine (APIC)", col("e_affine")),
                    ("gravitational", rel("e_grav")),
                    ("stored", col("e_int")),
                    ("dissipated", col("d_visc")),
                    ("total", rel("e_total")),
                ],
                log: false,
            },
            Panel {
                ylabel: axis_label("injected", "energy_injected", false),
                lines: vec![("energy injected", col("energy_injected"))],
                log: false,
            },
            Panel {
                ylabel: "a/g, jump m/s (log)".into(),
                lines: vec![
                    ("max a/g", col("max_accel_g")),
                    ("max velocity jump (m/s)", col("max_jump")),
                ],
                log: true,
            },
            Panel {
                ylabel: "checkerboard".into(),
                lines: vec![
                    ("cell means (share)", col("checkerboard_means")),
                    ("nodal (of rho g h)", col("checkerboard_nodal")),
                    ("cell (of rho g h)", col("checkerboard_cell")),
                ],
                log: false,
            },
            Panel {
                ylabel: axis_label("departure", "hydro_rel_rms", true),
                lines: vec![
                    ("hydro rel. RMS", col("hydro_rel_rms")),
                    ("its floor (exact rest field)", col("hydro_floor_rel_rms")),
                    ("excess over the floor", col("hydro_excess_rel_rms")),
                    ("hydro max / rho0 g H", col("hydro_max")),
                    (
                        "not explained by accelerations",
                        col("hydro_unexplained_rel_rms"),
                    ),
                ],
                log: true,
            },
        ]
    }
}

impl Figure for TimeseriesFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1100, 1300)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res {
        let root = titled(root, &self.title, 22)?;
        let panels = self.panels();
        let areas = root.split_evenly((panels.len(), 1));
        let t_max = self.series.t.iter().copied().fold(0.0, f64::max).max(1e-9);
        for (k, (panel, area)) in panels.iter().zip(areas.iter()).enumerate() {
            let (lo, hi) = finite_range(&panel.lines, panel.log);
            let at = PanelAt {
                first: k == 0,
                last: k + 1 == panels.len(),
                t_max,
            };
            if panel.log {
                self.draw_panel(area, panel, at, LogAxis::new(lo, hi), &log_label)?;
            } else {
                let y: RangedCoordf64 = (lo..hi).into();
                self.draw_panel(area, panel, at, y, &|v| short(*v))?;
            }
        }
        Ok(())
    }
}

/// Where a panel sits in the stack and the shared time range.
#[derive(Clone, Copy)]
struct PanelAt {
    first: bool,
    last: bool,
    t_max: f64,
}

impl TimeseriesFigure<'_> {
    /// One panel on a y axis `y`: linear, or log10 ([`LogAxis`], the values
    /// then drawn as log10 and only the positive ones).
    fn draw_panel<DB, Y>(
        &self,
        area: &DrawingArea<DB, Shift>,
        panel: &Panel,
        at: PanelAt,
        y: Y,
        y_fmt: &dyn Fn(&f64) -> String,
    ) -> Res
    where
        DB: DrawingBackend,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let t = &self.series.t;
        let (lo, hi) = (y.range().start, y.range().end);
        let mut chart = ChartBuilder::on(area)
            .margin(6)
            .margin_right(20)
            .x_label_area_size(if at.last { 44 } else { 22 })
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..at.t_max, y)
            .map_err(err)?;
        let mut mesh = chart.configure_mesh();
        mesh.y_desc(panel.ylabel.as_str())
            .label_style((SANS, 13))
            .axis_desc_style((SANS, 15))
            .y_label_formatter(y_fmt)
            .x_label_formatter(&|v| short(*v));
        if at.last {
            mesh.x_desc("time t (s)");
        }
        mesh.draw().map_err(err)?;
        for (i, (name, v)) in panel.lines.iter().enumerate() {
            let colour = series_colour(i);
            let pts: Vec<(f64, f64)> = t
                .iter()
                .zip(v)
                .filter(|(_, y)| y.is_finite() && (!panel.log || **y > 0.0))
                .map(|(x, y)| (*x, if panel.log { y.log10() } else { *y }))
                .collect();
            chart
                .draw_series(LineSeries::new(pts, colour.stroke_width(2)))
                .map_err(err)?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2))
                });
        }
        for m in self.markers {
            chart
                .draw_series(LineSeries::new([(m.t, lo), (m.t, hi)], m.colour.mix(0.7)))
                .map_err(err)?;
            if at.first {
                chart
                    .draw_series([Text::new(
                        format!("#{}{}", m.id, m.note),
                        (m.t, hi - 0.02 * (hi - lo)),
                        (SANS, 13).into_font().color(&m.colour),
                    )])
                    .map_err(err)?;
            }
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight, 13)
    }
}

/// Surge front Z(T) with the Martin & Moyce points.
pub struct FrontFigure<'a> {
    pub t: &'a [f64],
    pub z: &'a [f64],
    pub data: &'a [(f64, f64)],
    pub z_wall: f64,
    pub title: String,
}

impl Figure for FrontFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (800, 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res {
        let t_max = self
            .t
            .iter()
            .copied()
            .filter(|x| x.is_finite())
            .fold(1.0, f64::max)
            .min(12.0);
        let z_max = self.z_wall * 1.1;
        let mut chart = ChartBuilder::on(root)
            .margin(12)
            .margin_top(12 + draw_title(root, &self.title, 20)?)
            .x_label_area_size(46)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_max, 0.0..z_max)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("T = t sqrt(2g/a)")
            .y_desc("Z = x_front / a")
            .label_style((SANS, 14))
            .axis_desc_style((SANS, 16))
            .draw()
            .map_err(err)?;
        let sim: Vec<(f64, f64)> = self
            .t
            .iter()
            .zip(self.z)
            .filter(|(t, z)| t.is_finite() && z.is_finite() && **t <= t_max)
            .map(|(t, z)| (*t, *z))
            .collect();
        let blue = series_colour(0);
        chart
            .draw_series(LineSeries::new(sim, blue.stroke_width(2)))
            .map_err(err)?
            .label("this case")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], blue.stroke_width(2)));
        chart
            .draw_series(
                self.data
                    .iter()
                    .filter(|(t, z)| *t <= t_max && *z <= z_max)
                    .map(|&(t, z)| Circle::new((t, z), 5, BLACK.filled())),
            )
            .map_err(err)?
            .label("Martin & Moyce 1952")
            .legend(|(x, y)| Circle::new((x + 9, y), 5, BLACK.filled()));
        chart
            .draw_series(LineSeries::new(
                [(0.0, self.z_wall), (t_max, self.z_wall)],
                BLACK.mix(0.4),
            ))
            .map_err(err)?
            .label("far wall")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], BLACK.mix(0.4)));
        legend(&mut chart, SeriesLabelPosition::LowerRight, 14)?;
        Ok(())
    }
}

/// Pressure against depth below the settled free surface, with the hydrostatic line.
pub struct PressureDepthFigure<'a> {
    pub snap: &'a Snapshot,
    /// Settled water level (m), density and gravity.
    pub level: f64,
    pub rho0: f64,
    pub gravity: f64,
    pub title: String,
}

impl Figure for PressureDepthFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (800, 600)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res {
        let depth: Vec<f64> = self.snap.x.iter().map(|x| self.level - x.y).collect();
        let p_kpa: Vec<f64> = self.snap.pressure.iter().map(|p| p / 1e3).collect();
        let d_max = depth.iter().copied().fold(self.level, f64::max) * 1.05;
        let d_min = depth.iter().copied().fold(0.0, f64::min);
        let p_line = self.rho0 * self.gravity * d_max / 1e3;
        let finite = p_kpa.iter().copied().filter(|p| p.is_finite());
        let (p_lo, p_hi) = finite.fold((0.0f64, p_line), |(a, b), p| (a.min(p), b.max(p)));
        let mut chart = ChartBuilder::on(root)
            .margin(12)
            .margin_top(12 + draw_title(root, &self.title, 20)?)
            .x_label_area_size(46)
            .y_label_area_size(60)
            .build_cartesian_2d(p_lo..p_hi * 1.05, d_max..d_min)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("pressure p (kPa)")
            .y_desc("depth below settled surface (m)")
            .label_style((SANS, 14))
            .axis_desc_style((SANS, 16))
            .draw()
            .map_err(err)?;
        let blue = series_colour(0);
        chart
            .draw_series(
                p_kpa
                    .iter()
                    .zip(&depth)
                    .filter(|(p, _)| p.is_finite())
                    .map(|(p, d)| Circle::new((*p, *d), 2, blue.mix(0.5).filled())),
            )
            .map_err(err)?
            .label("particles")
            .legend(move |(x, y)| Circle::new((x + 9, y), 3, blue.filled()));
        let (d0, d1) = (d_min.max(0.0), d_max);
        let line = [
            (self.rho0 * self.gravity * d0 / 1e3, d0),
            (self.rho0 * self.gravity * d1 / 1e3, d1),
        ];
        chart
            .draw_series(LineSeries::new(line, BLACK.stroke_width(2)))
            .map_err(err)?
            .label("hydrostatic rho0 g d")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], BLACK.stroke_width(2)));
        legend(&mut chart, SeriesLabelPosition::UpperRight, 14)?;
        Ok(())
    }
}

/// Region outlined on maps (metres).
#[derive(Clone, Copy, Debug)]
pub struct Outline {
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

/// What a map colours particles by.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MapField {
    PressureKpa,
    AccelG,
}

impl MapField {
    fn values(&self, s: &Snapshot, g: f64) -> Vec<f64> {
        match self {
            MapField::PressureKpa => s.pressure.iter().map(|p| p / 1e3).collect(),
            MapField::AccelG => s.accel.iter().map(|a| a / g).collect(),
        }
    }
    fn label(&self) -> &'static str {
        match self {
            MapField::PressureKpa => "pressure (kPa)",
            MapField::AccelG => "a/g (log)",
        }
    }
}

/// Where a map is drawn: the box, an optional outlined region and g (for a/g).
#[derive(Clone, Copy, Debug)]
pub struct MapFrame {
    pub bbox: [f64; 4],
    pub outline: Option<Outline>,
    pub gravity: f64,
}

/// One map panel: particles in the box coloured by a field, with colour bar.
pub fn draw_map<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    snap: &Snapshot,
    field: MapField,
    scale: &ColourScale,
    frame: MapFrame,
    title: &str,
) -> Res {
    let (bbox, outline, g) = (frame.bbox, frame.outline, frame.gravity);
    let (w, _) = area.dim_in_pixel();
    let (map, bar) = area.split_horizontally(w.saturating_sub(125));
    let mut chart = ChartBuilder::on(&map)
        .margin(6)
        .margin_top(6 + draw_title(&map, title, 16)?)
        .x_label_area_size(40)
        .y_label_area_size(52)
        .build_cartesian_2d(bbox[0]..bbox[2], bbox[1]..bbox[3])
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style((SANS, 12))
        .axis_desc_style((SANS, 14))
        .x_labels(5)
        .y_labels(4)
        .draw()
        .map_err(err)?;
    let values = field.values(snap, g);
    let (mw, _) = map.dim_in_pixel();
    let radius = ((mw as f64 / 400.0) * 1.6).clamp(1.0, 3.0) as i32;
    chart
        .draw_series(
            snap.x
                .iter()
                .zip(&values)
                .filter(|(x, _)| x.x.is_finite() && x.y.is_finite())
                .map(|(x, v)| Circle::new((x.x, x.y), radius, scale.colour(*v).filled())),
        )
        .map_err(err)?;
    if let Some(o) = outline {
        chart
            .draw_series([Rectangle::new(
                [(o.x0, o.y0), (o.x1, o.y1)],
                RED.stroke_width(2),
            )])
            .map_err(err)?;
    }
    colour_bar(&bar, scale, field.label())
}

/// A row of maps of one field at several snapshots, and of a second field below.
pub struct MapsFigure<'a> {
    pub snaps: Vec<(&'a Snapshot, String)>,
    pub bbox: [f64; 4],
    pub outline: Option<Outline>,
    pub gravity: f64,
    pub title: String,
}

impl Figure for MapsFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let cols = self.snaps.len().max(1) as u32;
        let aspect = (self.bbox[3] - self.bbox[1]) / (self.bbox[2] - self.bbox[0]);
        (cols * 520, 2 * (aspect * 400.0) as u32 + 150)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res {
        let root = titled(root, &self.title, 20)?;
        let cells = root.split_evenly((2, self.snaps.len().max(1)));
        let all = |f: MapField| -> Vec<f64> {
            self.snaps
                .iter()
                .flat_map(|(s, _)| f.values(s, self.gravity))
                .collect()
        };
        let p_scale = ColourScale::robust(&all(MapField::PressureKpa), false);
        let mut a_scale = ColourScale::robust(&all(MapField::AccelG), true);
        a_scale.lo = a_scale.lo.max(a_scale.hi * 1e-4);
        for (k, (snap, label)) in self.snaps.iter().enumerate() {
            let frame = MapFrame {
                bbox: self.bbox,
                outline: self.outline,
                gravity: self.gravity,
            };
            draw_map(
                &cells[k],
                snap,
                MapField::PressureKpa,
                &p_scale,
                frame,
                label,
            )?;
            let cell = &cells[self.snaps.len() + k];
            draw_map(cell, snap, MapField::AccelG, &a_scale, frame, label)?;
        }
        Ok(())
    }
}

/// An animated GIF of the frames (pressure maps), 250 ms per frame.
pub fn animate(
    frames: &[Snapshot],
    bbox: [f64; 4],
    outline: Option<Outline>,
    title: &str,
    path: &Path,
    gravity: f64,
) -> Res {
    fonts();
    let all: Vec<f64> = frames
        .iter()
        .flat_map(|s| s.pressure.iter().map(|p| p / 1e3))
        .collect();
    let scale = ColourScale::robust(&all, false);
    let aspect = (bbox[3] - bbox[1]) / (bbox[2] - bbox[0]);
    let size = (760, (aspect * 620.0) as u32 + 80);
    let tmp = path.with_extension(format!("tmp{}.gif", std::process::id()));
    {
        let root = BitMapBackend::gif(&tmp, size, 250)
            .map_err(err)?
            .into_drawing_area();
        for f in frames {
            root.fill(&WHITE).map_err(err)?;
            let label = format!("{title}: step {}, t = {:.4} s", f.step, f.t);
            let frame = MapFrame {
                bbox,
                outline,
                gravity,
            };
            draw_map(&root, f, MapField::PressureKpa, &scale, frame, &label)?;
            root.present().map_err(err)?;
        }
    }
    std::fs::rename(&tmp, path).map_err(err)
}
