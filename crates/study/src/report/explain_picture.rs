//! `kick explain`'s picture: the event's cells at the onset window's start
//! and at the event's first step, with the event particles' stencil nodes
//! (disc area by mass share, red below the small-mass share), their net
//! nodal forces (internal + gravity, and the pressure under the
//! pressure-implicit formulation; scaled to the largest) as arrows, and
//! the particles whose stress reached them coloured by pressure; the
//! event's particles ringed in black.

use crate::report::plot::{colour_bar, draw_title, err, render, ColourScale, Figure, Res, SANS};
use monitor::mechanisms::SMALL_NODE_SHARE;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use solver::forensics::ExplainedStep;
use solver::Vec2;
use std::collections::BTreeSet;
use std::path::Path;

struct Picture<'a> {
    frames: [(&'a ExplainedStep, &'static str); 2],
    h: f64,
    lo: Vec2,
    hi: Vec2,
    pressure: ColourScale,
}

/// The contributing particles of a frame (sorted, unique).
fn contributors(f: &ExplainedStep) -> BTreeSet<usize> {
    f.explained
        .iter()
        .flat_map(|e| e.stresses.iter().map(|s| s.particle))
        .collect()
}

pub fn write(before: &ExplainedStep, onset: &ExplainedStep, h: f64, dir: &Path) -> Res {
    let mut lo = Vec2::repeat(f64::INFINITY);
    let mut hi = Vec2::repeat(f64::NEG_INFINITY);
    let mut pressures = vec![];
    for f in [before, onset] {
        for e in &f.explained {
            for n in &e.nodes {
                lo = lo.inf(&n.position);
                hi = hi.sup(&n.position);
            }
        }
        pressures.extend(contributors(f).into_iter().map(|q| f.pressure[q]));
    }
    if !lo.x.is_finite() {
        return Ok(());
    }
    let pad = Vec2::repeat(h);
    let pic = Picture {
        frames: [
            (before, "onset window start"),
            (onset, "event's first step"),
        ],
        h,
        lo: lo - pad,
        hi: hi + pad,
        pressure: ColourScale::robust(&pressures, false),
    };
    render(&pic, dir, "explain_cells").map(|_| ())
}

impl Figure for Picture<'_> {
    fn size(&self) -> (u32, u32) {
        (1300, 620)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res {
        let (main, bar) = root.split_horizontally(1180);
        let panels = main.split_evenly((1, 2));
        for (area, (frame, title)) in panels.iter().zip(self.frames) {
            self.panel(area, frame, title)?;
        }
        colour_bar(&bar, &self.pressure, "pressure (Pa)")?;
        Ok(())
    }
}

/// A panel's chart: metres on both axes.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

impl Picture<'_> {
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        f: &ExplainedStep,
        title: &str,
    ) -> Res {
        let mut chart = ChartBuilder::on(area)
            .margin(10)
            .margin_top(10 + draw_title(area, &format!("{title}: t = {:.5} s", f.time), 18)?)
            .x_label_area_size(35)
            .y_label_area_size(50)
            .build_cartesian_2d(self.lo.x..self.hi.x, self.lo.y..self.hi.y)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .label_style((SANS, 12))
            .draw()
            .map_err(err)?;
        self.cell_lines(&mut chart)?;
        self.particles(&mut chart, f)?;
        self.nodes(&mut chart, f)?;
        Ok(())
    }

    /// The grid's cell lines over the panel.
    fn cell_lines<DB: DrawingBackend>(&self, chart: &mut Chart<DB>) -> Res {
        let lines = |lo: f64, hi: f64| {
            let first = (lo / self.h).ceil() as i64;
            let last = (hi / self.h).floor() as i64;
            (first..=last)
                .map(|k| k as f64 * self.h)
                .collect::<Vec<f64>>()
        };
        let grey = RGBColor(200, 200, 200);
        for x in lines(self.lo.x, self.hi.x) {
            chart
                .draw_series(LineSeries::new([(x, self.lo.y), (x, self.hi.y)], grey))
                .map_err(err)?;
        }
        for y in lines(self.lo.y, self.hi.y) {
            chart
                .draw_series(LineSeries::new([(self.lo.x, y), (self.hi.x, y)], grey))
                .map_err(err)?;
        }
        Ok(())
    }

    /// The contributing particles by pressure; the event's particles ringed.
    fn particles<DB: DrawingBackend>(&self, chart: &mut Chart<DB>, f: &ExplainedStep) -> Res {
        let inside =
            |x: Vec2| x.x >= self.lo.x && x.x <= self.hi.x && x.y >= self.lo.y && x.y <= self.hi.y;
        for q in contributors(f) {
            let x = f.x[q];
            if inside(x) {
                let c = self.pressure.colour(f.pressure[q]);
                chart
                    .draw_series([Circle::new((x.x, x.y), 4, c.filled())])
                    .map_err(err)?;
            }
        }
        for e in &f.explained {
            let x = f.x[e.particle];
            chart
                .draw_series([Circle::new((x.x, x.y), 7, BLACK.stroke_width(2))])
                .map_err(err)?;
        }
        Ok(())
    }

    /// The stencil nodes: disc area by mass share (red: light); force
    /// arrows scaled to the largest.
    fn nodes<DB: DrawingBackend>(&self, chart: &mut Chart<DB>, f: &ExplainedStep) -> Res {
        let mut nodes: Vec<(Vec2, f64, Vec2)> = vec![];
        for e in &f.explained {
            for n in &e.nodes {
                if !nodes
                    .iter()
                    .any(|(p, _, _)| (p - n.position).norm() < 1e-9 * self.h)
                {
                    nodes.push((n.position, n.mass_share, n.force));
                }
            }
        }
        let f_max = nodes.iter().map(|n| n.2.norm()).fold(0.0, f64::max);
        for (p, share, force) in &nodes {
            let r = (10.0 * share.max(0.0).sqrt()).clamp(2.0, 14.0) as i32;
            let colour = if *share < SMALL_NODE_SHARE { RED } else { BLUE };
            chart
                .draw_series([Circle::new((p.x, p.y), r, colour.stroke_width(2))])
                .map_err(err)?;
            if f_max > 0.0 {
                let tip = p + force / f_max * 0.8 * self.h;
                chart
                    .draw_series(LineSeries::new(
                        [(p.x, p.y), (tip.x, tip.y)],
                        colour.stroke_width(2),
                    ))
                    .map_err(err)?;
            }
        }
        Ok(())
    }
}
