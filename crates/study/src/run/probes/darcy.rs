//! Darcy's column (docs/physics.md section 6): the pressure drop across a
//! fixed layer under gravity against Darcy's law, and the flux.

use super::mixture_scene::fixed_layer;
use crate::output::metrics::line_fit;
use crate::output::summary::Check;
use crate::run::{Probe, Run, Simulated};
use crate::study_file::MixtureSpec;
use serde::{Deserialize, Serialize};
use solver::{Mixture, Phase, Scene, StateView};

/// The Darcy column: a fixed layer (below) under gravity.
pub fn darcy_layer(scene: &Scene, spec: &MixtureSpec) -> Option<[f64; 2]> {
    fixed_layer(scene, spec).filter(|_| scene.gravity > 0.0)
}

/// Darcy's figures from the fluid's state: (relative error of the layer's
/// pressure drop against mu q L / k = B q L / n^2, linearity of p inside the
/// layer relative to that drop, from three rows up; the flux q). Rows of one cell; the layer's
/// gradient from rows at least one cell inside its faces, the free fluid's
/// from rows at least two cells away from them.
fn darcy_figures(
    v: &StateView,
    layer: [f64; 2],
    b: f64,
    n: f64,
) -> Option<(f64, Option<f64>, f64)> {
    let h = v.scene.cell;
    let (y_lo, height) = (v.scene.origin[1], v.scene.size[1]);
    let rows = (height / h).round() as usize;
    let mut sum = vec![(0.0, 0.0, 0usize); rows];
    for ((x, p), vel) in v.x.iter().zip(v.pressure).zip(v.v) {
        let r = (((x.y - y_lo) / h).floor().max(0.0) as usize).min(rows - 1);
        sum[r].0 += p;
        sum[r].1 += vel.y;
        sum[r].2 += 1;
    }
    let [y0, y1] = layer;
    let row = |r: usize| {
        let (lo, hi) = (y_lo + r as f64 * h, y_lo + (r + 1) as f64 * h);
        let (p, vy, c) = sum[r];
        (lo, hi, p / c.max(1) as f64, vy / c.max(1) as f64, c)
    };
    let eps = 1e-9 * h;
    let inside: Vec<_> = (0..rows)
        .map(row)
        .filter(|&(lo, hi, _, _, c)| c > 0 && lo >= y0 + h - eps && hi <= y1 - h + eps)
        .collect();
    let far = |lo: f64, hi: f64| hi <= y0 - 2.0 * h + eps || lo >= y1 + 2.0 * h - eps;
    let above: Vec<(f64, f64)> = (0..rows)
        .map(row)
        .filter(|&(lo, hi, _, _, c)| c > 0 && far(lo, hi) && lo >= y1)
        .map(|(lo, hi, p, _, _)| (0.5 * (lo + hi), p))
        .collect();
    let below: Vec<(f64, f64)> = (0..rows)
        .map(row)
        .filter(|&(lo, hi, _, _, c)| c > 0 && far(lo, hi) && hi <= y0)
        .map(|(lo, hi, p, _, _)| (0.5 * (lo + hi), p))
        .collect();
    let pts: Vec<(f64, f64)> = inside
        .iter()
        .map(|&(lo, hi, p, _, _)| (0.5 * (lo + hi), p))
        .collect();
    let (s_in, a_in) = line_fit(&pts)?;
    let outside: Vec<(f64, usize)> = [&above, &below]
        .iter()
        .filter_map(|pts| line_fit(pts).map(|(s, _)| (s, pts.len())))
        .collect();
    let weight: usize = outside.iter().map(|o| o.1).sum();
    if weight == 0 {
        return None;
    }
    let s_out = outside.iter().map(|o| o.0 * o.1 as f64).sum::<f64>() / weight as f64;
    // Darcy flux (downward positive): n times the fluid's speed in the layer.
    let q = -n * inside.iter().map(|r| r.3).sum::<f64>() / inside.len() as f64;
    let expected = b * q / (n * n);
    let error = ((s_in - s_out) - expected).abs() / expected.abs();
    let drop = expected.abs() * (y1 - y0);
    // A line through two rows says nothing about linearity.
    let linearity = (pts.len() >= 3).then(|| {
        pts.iter()
            .map(|&(y, p)| (p - (a_in + s_in * y)).abs())
            .fold(0.0, f64::max)
            / drop
    });
    Some((error, linearity, q))
}

/// The Darcy column (a fixed layer in a periodic box under gravity), at
/// t_end: |drop - mu q L / k| / (mu q L / k) with the drop from the
/// pressure gradients fitted inside and outside the layer, the largest
/// departure of the layer's row-averaged pressure from its line over that
/// drop, the measured Darcy flux q (m/s), and |q - q_ideal| / q_ideal with
/// q_ideal = rho g H n^2 / (B L), the flux at which the layer's drop
/// carries the whole column's weight (the node-based drag acts over a
/// layer about a cell longer than L).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DarcyFigures {
    pub dp_rel_error: f64,
    pub linearity: Option<f64>,
    pub flux: f64,
    pub flux_rel_error: f64,
}

impl Check for DarcyFigures {
    const NAME: &'static str = "darcy";
}

/// Darcy's figures at the end of a run of the Darcy column.
pub struct DarcyColumn {
    layer: [f64; 2],
    /// The fluid's volume fraction and the drag coefficient there.
    n: f64,
    b: f64,
    gravity: f64,
    height: f64,
}

impl DarcyColumn {
    pub fn new(scene: &Scene, spec: &MixtureSpec) -> Option<Self> {
        let layer = darcy_layer(scene, spec)?;
        let n = scene
            .bodies
            .iter()
            .find(|b| b.phase == Some(Phase::Fluid))
            .map_or(1.0, |b| b.fraction);
        Some(DarcyColumn {
            layer,
            n,
            b: spec.drag.coefficient_at(n),
            gravity: scene.gravity,
            height: scene.size[1],
        })
    }
}

impl Probe<Mixture> for DarcyColumn {
    fn finish(&mut self, run: &Run<Mixture>, outcome: &mut Simulated) -> std::io::Result<()> {
        let fluid = run.stepper.phase(1).view();
        let (n, b) = (self.n, self.b);
        let Some((error, linearity, q)) = darcy_figures(&fluid, self.layer, b, n) else {
            return Ok(());
        };
        // The column's weight balances the layer's drop: q = rho g H n^2 / (B L).
        let rho = fluid.materials[fluid.material[0] as usize].rho0;
        let ideal =
            rho * self.gravity * self.height * n * n / (b * (self.layer[1] - self.layer[0]));
        outcome.metrics.set_check(&DarcyFigures {
            dp_rel_error: error,
            linearity,
            flux: q,
            flux_rel_error: (q - ideal).abs() / ideal,
        });
        Ok(())
    }
}
