//! Matrix figures: outcome and accuracy heatmaps over two axes (one panel
//! per value of a third), the stability map and speed against accuracy with
//! its Pareto front.

use crate::report::plot::{
    colour_bar, draw_title, err, legend, log_label, series_colour, short, titled, ColourScale,
    Figure, LogAxis, Res, SANS,
};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

pub struct HeatCell {
    pub x: usize,
    pub y: usize,
    pub colour: RGBColor,
    pub text: String,
}

pub struct HeatPanel {
    pub title: String,
    pub cells: Vec<HeatCell>,
}

pub enum HeatKey {
    /// Categorical legend: label and colour.
    Legend(Vec<(String, RGBColor)>),
    /// Continuous colour bar.
    Bar(ColourScale, String),
}

pub struct HeatmapFigure {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_cats: Vec<String>,
    pub y_cats: Vec<String>,
    pub panels: Vec<HeatPanel>,
    pub key: HeatKey,
}

impl Figure for HeatmapFigure {
    fn size(&self) -> (u32, u32) {
        let w = 140 + 110 * self.x_cats.len().max(1) as u32;
        let (cols, rows) = self.grid();
        (
            cols * w + 180,
            40 + rows * (130 + 60 * self.y_cats.len().max(1) as u32),
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res {
        let root = titled(root, &self.title, 20)?;
        let (w, _) = root.dim_in_pixel();
        let (plots, key) = root.split_horizontally(w.saturating_sub(170));
        let (cols, rows) = self.grid();
        let areas = plots.split_evenly((rows as usize, cols as usize));
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            self.draw_panel(panel, area)?;
        }
        match &self.key {
            HeatKey::Bar(scale, label) => colour_bar(&key, scale, label)?,
            HeatKey::Legend(items) => {
                for (k, (label, colour)) in items.iter().enumerate() {
                    let y = 40 + 28 * k as i32;
                    key.draw(&Rectangle::new([(10, y), (30, y + 18)], colour.filled()))
                        .map_err(err)?;
                    key.draw(&Text::new(label.clone(), (38, y + 2), (SANS, 14)))
                        .map_err(err)?;
                }
            }
        }
        Ok(())
    }
}

/// Panels side by side up to this many, then the next row.
const PANELS_PER_ROW: usize = 4;

impl HeatmapFigure {
    /// Columns and rows of panels.
    fn grid(&self) -> (u32, u32) {
        let n = self.panels.len().max(1);
        let cols = n.min(PANELS_PER_ROW);
        (cols as u32, n.div_ceil(cols) as u32)
    }

    /// One panel: the categories on both axes and a labelled square per cell.
    fn draw_panel<DB: DrawingBackend>(
        &self,
        panel: &HeatPanel,
        area: &DrawingArea<DB, Shift>,
    ) -> Res {
        let (nx, ny) = (self.x_cats.len() as i32, self.y_cats.len() as i32);
        let longest = self.y_cats.iter().map(|c| c.len()).max().unwrap_or(4) as u32;
        let mut chart = ChartBuilder::on(area)
            .margin(8)
            .margin_top(8 + draw_title(area, &panel.title, 16)?)
            .x_label_area_size(50)
            .y_label_area_size(30 + 7 * longest)
            .build_cartesian_2d(
                (0..(nx - 1).max(0)).into_segmented(),
                (0..(ny - 1).max(0)).into_segmented(),
            )
            .map_err(err)?;
        let xc = |v: &SegmentValue<i32>| match v {
            SegmentValue::CenterOf(k) => self.x_cats.get(*k as usize).cloned().unwrap_or_default(),
            _ => String::new(),
        };
        let yc = |v: &SegmentValue<i32>| match v {
            SegmentValue::CenterOf(k) => self.y_cats.get(*k as usize).cloned().unwrap_or_default(),
            _ => String::new(),
        };
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .x_labels(nx as usize)
            .y_labels(ny as usize)
            .x_label_formatter(&xc)
            .y_label_formatter(&yc)
            .label_style((SANS, 13))
            .axis_desc_style((SANS, 14))
            .draw()
            .map_err(err)?;
        for c in &panel.cells {
            let (x, y) = (c.x as i32, c.y as i32);
            chart
                .draw_series([Rectangle::new(
                    [
                        (SegmentValue::Exact(x), SegmentValue::Exact(y)),
                        (SegmentValue::Exact(x + 1), SegmentValue::Exact(y + 1)),
                    ],
                    c.colour.filled(),
                )])
                .map_err(err)?;
            let light = (c.colour.0 as u32 + c.colour.1 as u32 + c.colour.2 as u32) > 400;
            let ink = if light { BLACK } else { WHITE };
            chart
                .draw_series([Text::new(
                    c.text.clone(),
                    (SegmentValue::CenterOf(x), SegmentValue::CenterOf(y)),
                    (SANS, 13)
                        .into_font()
                        .color(&ink)
                        .pos(plotters::style::text_anchor::Pos::new(
                            plotters::style::text_anchor::HPos::Center,
                            plotters::style::text_anchor::VPos::Center,
                        )),
                )])
                .map_err(err)?;
        }
        Ok(())
    }
}

/// Lines of y against x (x on a log axis when `x_log`), e.g. survival time against K.
pub struct LinesFigure {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub lines: Vec<(String, Vec<(f64, f64)>)>,
    /// Per line, (x, y_min, y_max) bars drawn around its points (e.g. the
    /// spread of an ensemble around its median); empty for none.
    pub spread: Vec<Vec<(f64, f64, f64)>>,
    pub x_log: bool,
    pub y_max: f64,
}

impl Figure for LinesFigure {
    fn size(&self) -> (u32, u32) {
        (900, 600)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res {
        let xs = self
            .lines
            .iter()
            .flat_map(|(_, p)| p.iter().map(|q| self.tx(q.0)));
        let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
        let (lo, hi) = if lo.is_finite() {
            (lo - 0.25, hi + 0.25)
        } else {
            (0.0, 1.0)
        };
        if self.x_log {
            self.draw_on(root, LogAxis::new(lo, hi), &log_label)
        } else {
            let x: RangedCoordf64 = (lo..hi).into();
            self.draw_on(root, x, &|v| short(*v))
        }
    }
}

impl LinesFigure {
    /// x as drawn: log10 of x on a log axis.
    fn tx(&self, x: f64) -> f64 {
        if self.x_log {
            x.log10()
        } else {
            x
        }
    }

    /// The figure on an x axis `x`: linear, or log10 ([`LogAxis`]).
    fn draw_on<DB, X>(
        &self,
        root: &DrawingArea<DB, Shift>,
        x: X,
        x_fmt: &dyn Fn(&f64) -> String,
    ) -> Res
    where
        DB: DrawingBackend,
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let mut chart = ChartBuilder::on(root)
            .margin(12)
            .margin_top(12 + draw_title(root, &self.title, 20)?)
            .x_label_area_size(46)
            .y_label_area_size(60)
            .build_cartesian_2d(x, 0.0..self.y_max * 1.08)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .x_label_formatter(x_fmt)
            .label_style((SANS, 14))
            .axis_desc_style((SANS, 16))
            .draw()
            .map_err(err)?;
        for (k, (name, pts)) in self.lines.iter().enumerate() {
            let colour = series_colour(k);
            let pts: Vec<(f64, f64)> = pts.iter().map(|(x, y)| (self.tx(*x), *y)).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(err)?
                .label(name.clone())
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 4, colour.filled())))
                .map_err(err)?;
            for &(x, y0, y1) in self.spread.get(k).map_or(&[][..], |v| v.as_slice()) {
                let x = self.tx(x);
                chart
                    .draw_series(LineSeries::new([(x, y0), (x, y1)], colour.stroke_width(1)))
                    .map_err(err)?;
            }
        }
        legend(&mut chart, SeriesLabelPosition::LowerRight, 12)?;
        Ok(())
    }
}

/// A chart with log10 axes labelled by decade, its mesh drawn.
fn log_log_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    [x, y]: [LogAxis; 2],
    [x_label, y_label]: [&str; 2],
) -> Res<ChartContext<'a, DB, Cartesian2d<LogAxis, LogAxis>>> {
    let mut chart = ChartBuilder::on(root)
        .margin(12)
        .margin_top(12 + draw_title(root, title, 20)?)
        .x_label_area_size(46)
        .y_label_area_size(70)
        .build_cartesian_2d(x, y)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&log_label)
        .y_label_formatter(&log_label)
        .label_style((SANS, 14))
        .axis_desc_style((SANS, 16))
        .draw()
        .map_err(err)?;
    Ok(chart)
}

/// Cost against error, one point per case, with the Pareto front (lower is better on both).
pub struct ParetoFigure {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub points: Vec<(String, f64, f64)>,
}

/// Indices of the non-dominated points, sorted by x.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len()).collect();
    idx.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut front = vec![];
    let mut best = f64::INFINITY;
    for i in idx {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

impl Figure for ParetoFigure {
    fn size(&self) -> (u32, u32) {
        (900, 640)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res {
        let pts: Vec<(f64, f64)> = self
            .points
            .iter()
            .filter(|(_, x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
            .map(|(_, x, y)| (x.log10(), y.log10()))
            .collect();
        let names: Vec<&String> = self
            .points
            .iter()
            .filter(|(_, x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
            .map(|(n, _, _)| n)
            .collect();
        let range = |f: fn(&(f64, f64)) -> f64| {
            let (a, b) = pts
                .iter()
                .map(f)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
            if a.is_finite() {
                (a - 0.3, b + 0.3)
            } else {
                (0.0, 1.0)
            }
        };
        let (x0, x1) = range(|p| p.0);
        let (y0, y1) = range(|p| p.1);
        let y_axis = LogAxis::new(y0, y1);
        let (y0, y1) = (y_axis.range().start, y_axis.range().end);
        let mut chart = log_log_chart(
            root,
            &self.title,
            [LogAxis::new(x0, x1), y_axis],
            [&self.x_label, &self.y_label],
        )?;
        let blue = series_colour(0);
        chart
            .draw_series(
                pts.iter()
                    .map(|p| Circle::new(*p, 5, blue.mix(0.7).filled())),
            )
            .map_err(err)?
            .label("case")
            .legend(move |(x, y)| Circle::new((x + 9, y), 5, blue.filled()));
        let front = pareto_front(&pts);
        let red = series_colour(3);
        chart
            .draw_series(LineSeries::new(
                front.iter().map(|&i| pts[i]),
                red.stroke_width(2),
            ))
            .map_err(err)?
            .label("Pareto front")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], red.stroke_width(2)));
        for (k, &i) in front.iter().enumerate() {
            let dy = if k % 2 == 0 { 0.04 } else { -0.08 } * (y1 - y0);
            chart
                .draw_series([Text::new(
                    names[i].clone(),
                    (pts[i].0, pts[i].1 + dy),
                    (SANS, 12),
                )])
                .map_err(err)?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight, 13)?;
        Ok(())
    }
}

/// Error against cell size on log-log axes, one line per case, with dashed
/// reference lines of slope 1 and 2 through the middle of the data.
pub struct RefinementFigure {
    pub title: String,
    pub y_label: String,
    /// (name, [(h, error)]), errors > 0.
    pub lines: Vec<(String, Vec<(f64, f64)>)>,
}

/// Most lines that get a legend entry (the rest are drawn unlabelled).
const REFINEMENT_LEGEND: usize = 12;

impl RefinementFigure {
    /// The lines' points as log10 (h, error), finite and positive only.
    fn log_lines(&self) -> Vec<(&String, Vec<(f64, f64)>)> {
        self.lines
            .iter()
            .map(|(name, pts)| {
                let pts = pts
                    .iter()
                    .filter(|(h, e)| *h > 0.0 && *e > 0.0 && h.is_finite() && e.is_finite())
                    .map(|(h, e)| (h.log10(), e.log10()))
                    .collect();
                (name, pts)
            })
            .collect()
    }

    /// Reference lines of slope 1 and 2 through the data's centre (log10
    /// h and error means), spanning its h range.
    pub fn reference_lines(&self) -> Vec<(f64, [(f64, f64); 2])> {
        let pts: Vec<(f64, f64)> = self.log_lines().into_iter().flat_map(|(_, p)| p).collect();
        if pts.is_empty() {
            return vec![];
        }
        let n = pts.len() as f64;
        let (cx, cy) = (
            pts.iter().map(|p| p.0).sum::<f64>() / n,
            pts.iter().map(|p| p.1).sum::<f64>() / n,
        );
        let (x0, x1) = pts
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.0), b.max(p.0))
            });
        [1.0, 2.0]
            .map(|s| (s, [(x0, cy + s * (x0 - cx)), (x1, cy + s * (x1 - cx))]))
            .to_vec()
    }
}

impl Figure for RefinementFigure {
    fn size(&self) -> (u32, u32) {
        (900, 640)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res {
        let lines = self.log_lines();
        let refs = self.reference_lines();
        let all = lines
            .iter()
            .flat_map(|(_, p)| p.iter().copied())
            .chain(refs.iter().flat_map(|(_, ends)| ends.iter().copied()));
        let (x0, x1, y0, y1) = all.fold(
            (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ),
            |(a, b, c, d), (x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
        );
        let (x0, x1, y0, y1) = if x0.is_finite() && y0.is_finite() {
            (x0 - 0.15, x1 + 0.15, y0 - 0.15, y1 + 0.15)
        } else {
            (-3.0, -1.0, -3.0, 0.0)
        };
        let mut chart = log_log_chart(
            root,
            &self.title,
            [LogAxis::new(x0, x1), LogAxis::new(y0, y1)],
            ["cell size h (m)", &self.y_label],
        )?;
        for &(slope, ends) in &refs {
            let style = RGBColor(120, 120, 120).stroke_width(if slope == 1.0 { 1 } else { 2 });
            chart
                .draw_series(DashedLineSeries::new(ends, 6, 4, style))
                .map_err(err)?
                .label(format!("slope {slope}"))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], style));
        }
        for (k, (name, pts)) in lines.iter().enumerate() {
            let colour = series_colour(k);
            let series = chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(err)?;
            if k < REFINEMENT_LEGEND {
                series.label((*name).clone()).legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            }
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 4, colour.filled())))
                .map_err(err)?;
        }
        legend(&mut chart, SeriesLabelPosition::LowerRight, 12)?;
        Ok(())
    }
}
