//! USF, USL and MUSL as orderings of the same stages.

use crate::config::{ForceKind, QuadratureKind, SchemeKind, TransferKind};
use crate::remedies::{GridStep, Step};
use crate::stages::p2g::{self, Terms};
use crate::stages::projection;
use crate::timing::lap;
use crate::{par, stages::g2p, stages::grid_update, stages::stress, Solver};
use std::time::Instant;

const MASS_MOMENTUM: Terms = Terms {
    mass: true,
    momentum: true,
    force: false,
};
const FORCE: Terms = Terms {
    mass: false,
    momentum: false,
    force: true,
};
const ALL: Terms = Terms {
    mass: true,
    momentum: true,
    force: true,
};
const MOMENTUM: Terms = Terms {
    mass: false,
    momentum: true,
    force: false,
};

/// Which grid velocity the stress stage differentiates.
#[derive(Clone, Copy)]
enum StressVelocity {
    /// `grid.vel` as it stands when the stress stage runs: the P2G velocity
    /// v^n under USF, the velocity re-projected from the updated particles
    /// under MUSL.
    Grid,
    /// `grid.vel_new`: v^{n+1} after the grid update (USL).
    Updated,
}

/// The stages of a step up to and including the grid update (v^{n+1} on the
/// grid): a multiphase step couples the phases' grids here (`drag`).
pub fn to_grid(s: &mut Solver, clock: &mut Instant) {
    if s.implicit() {
        // Its own order: u* from the viscous stress and gravity, then the pressure.
        p2g(s, ALL, clock);
        grid_velocities(s, clock);
        grid_update(s, clock);
        project(s, clock);
        return;
    }
    match s.cfg.method.scheme {
        SchemeKind::Usf => {
            p2g(s, MASS_MOMENTUM, clock);
            grid_velocities(s, clock);
            stress(s, StressVelocity::Grid, clock);
            p2g(s, FORCE, clock);
            grid_update(s, clock);
        }
        SchemeKind::Usl | SchemeKind::Musl => {
            p2g(s, ALL, clock);
            grid_velocities(s, clock);
            grid_update(s, clock);
        }
    }
}

/// The stages after the grid update: G2P, then the stress under USL and MUSL.
pub fn from_grid(s: &mut Solver, clock: &mut Instant) {
    if s.staggered() {
        let material = &s.cfg.scene.materials[0];
        let flip_alpha = match s.cfg.method.transfer {
            TransferKind::Flip => Some(s.cfg.method.flip_alpha),
            TransferKind::Pic => Some(0.0),
            _ => None,
        };
        s.dissipated += projection::mac::update_particles(
            &mut s.particles,
            &s.projection,
            &s.cfg.method.projection,
            material,
            &s.grid,
            flip_alpha,
            s.dt,
        );
        s.dissipated += projection::mac::correct_packing(
            &mut s.particles,
            &mut s.projection,
            &s.cfg.method.projection,
            material,
            &s.grid,
            s.gravity,
            s.dt,
        );
        s.apply_perturbations();
        lap(&mut s.times.g2p, clock);
        return;
    }
    if s.implicit() {
        g2p(s, clock);
        let material = &s.cfg.scene.materials[0];
        s.dissipated += projection::update_particles(
            &mut s.particles,
            &s.stencils,
            &s.shape,
            &s.grid,
            material,
            &mut s.projection,
            s.dt,
        );
        let settings = &s.cfg.method.projection;
        s.dissipated += projection::shift_particles(
            &mut s.particles,
            &s.stencils,
            &s.shape,
            &s.grid,
            settings,
            settings.checkerboard / material.rho0,
            s.gravity,
            &mut s.projection,
            s.dt,
        );
        lap(&mut s.times.stress, clock);
        return;
    }
    match s.cfg.method.scheme {
        SchemeKind::Usf => g2p(s, clock),
        SchemeKind::Usl => {
            g2p(s, clock);
            stress(s, StressVelocity::Updated, clock);
        }
        SchemeKind::Musl => {
            g2p(s, clock);
            // Re-project the updated particle velocities (weights of the step start).
            p2g(s, MOMENTUM, clock);
            let grid = &mut s.grid;
            par::keep_warm(|| grid_update::project_momentum(grid));
            lap(&mut s.times.grid, clock);
            stress(s, StressVelocity::Grid, clock);
        }
    }
}

// The grid stage is serial (a fraction of the particle stages): `keep_warm`
// keeps the pool's other worker awake for the particle stage that follows.
fn grid_velocities(s: &mut Solver, clock: &mut Instant) {
    let grid = &mut s.grid;
    s.ke_grid_p2g = par::keep_warm(|| grid_update::velocities(grid));
    lap(&mut s.times.grid, clock);
}

/// The pressure solve of the pressure-implicit step (`stages/projection.rs`),
/// its dissipation booked.
fn project(s: &mut Solver, clock: &mut Instant) {
    let inputs = projection::Inputs {
        particles: &s.particles,
        material: &s.cfg.scene.materials[0],
        settings: &s.cfg.method.projection,
        shape: s.cfg.method.shape,
        dt: s.dt,
    };
    if s.staggered() {
        let affine = s.cfg.method.transfer == TransferKind::Apic;
        projection::mac::project(&inputs, s.gravity, affine, &mut s.grid, &mut s.projection);
        // The transfer's share of the budget is the faces' (the nodal
        // grid's P2G only feeds the monitor).
        s.ke_grid_p2g = s.projection.faces.kinetic(false);
    } else {
        projection::project(&inputs, &mut s.grid, &mut s.projection);
    }
    let stats = s.projection.stats;
    s.dissipated += stats.dissipated_projection + stats.dissipated_hourglass;
    lap(&mut s.times.grid, clock);
}

fn grid_update(s: &mut Solver, clock: &mut Instant) {
    let (grid, dt, gravity) = (&mut s.grid, s.dt, s.gravity);
    par::keep_warm(|| grid_update::update(grid, dt, gravity));
    if !s.remedies.is_empty() {
        let mut g = GridStep {
            grid: &mut s.grid,
            particles: &s.particles,
            stencils: &s.stencils,
            shape: &s.shape,
            dt: s.dt,
            gravity: s.gravity,
        };
        s.remedies.after_grid_update(&mut g);
    }
    lap(&mut s.times.grid, clock);
}

/// The particle side of the step as the remedies' hooks see it.
macro_rules! step_view {
    ($s:expr) => {
        Step {
            particles: &mut $s.particles,
            stencils: &$s.stencils,
            shape: &$s.shape,
            grid: &$s.grid,
            materials: &$s.cfg.scene.materials,
            dt: $s.dt,
            gravity: $s.cfg.scene.gravity,
        }
    };
}

fn p2g(s: &mut Solver, terms: Terms, clock: &mut Instant) {
    let inputs = p2g::Inputs {
        particles: &s.particles,
        stencils: &s.stencils,
        shape: &s.shape,
        bins: &s.bins,
        affine: match s.cfg.method.transfer {
            TransferKind::Apic => true,
            TransferKind::Flip => s.cfg.method.gradient_enhanced,
            _ => false,
        },
        mls: match s.cfg.method.force {
            ForceKind::Mls => s.shape.apic_inverse_inertia(),
            ForceKind::Gradient => None,
        },
        gravity: s.gravity,
        pressure_free: s.implicit(),
    };
    let mixed = terms.force && s.cfg.method.quadrature == QuadratureKind::Mixed;
    let scattered = Terms {
        force: terms.force && !mixed,
        ..terms
    };
    p2g::p2g(&inputs, scattered, &mut s.grid);
    if mixed {
        let rho0 = s.cfg.first_rho0();
        crate::stages::quadrature_mixed::forces(
            &s.particles,
            &s.stencils,
            &s.shape,
            &mut s.grid,
            s.gravity,
            rho0,
            &mut s.quadrature,
        );
    }
    if terms.mass {
        let grid = &s.grid;
        s.grid_mass_p2g =
            par::keep_warm(|| grid.active.iter().map(|&n| grid.mass_raw[n as usize]).sum());
    }
    lap(&mut s.times.p2g, clock);
}

fn stress(s: &mut Solver, which: StressVelocity, clock: &mut Instant) {
    if !s.remedies.is_empty() {
        s.remedies.before_stress(&mut step_view!(s));
    }
    let velocity = match which {
        StressVelocity::Grid => &s.grid.vel,
        StressVelocity::Updated => &s.grid.vel_new,
    };
    let inputs = stress::Inputs {
        stencils: &s.stencils,
        shape: &s.shape,
        grid: &s.grid,
        velocity,
        materials: &s.cfg.scene.materials,
        j_update: s.cfg.method.j_update,
        dt: s.dt,
        mls: s.cfg.method.force == ForceKind::Mls,
        rules: &s.remedies.points,
        drop_inverted: s.cfg.scene.on_inversion == crate::config::OnLoss::Delete,
    };
    let (dissipated, rule_work) = stress::update(&inputs, &mut s.particles, &mut s.partials_stress);
    s.dissipated += dissipated;
    if !s.remedies.is_empty() {
        s.remedies.book_point_work(&rule_work);
        s.remedies.after_stress(&mut step_view!(s));
    }
    lap(&mut s.times.stress, clock);
}

fn g2p(s: &mut Solver, clock: &mut Instant) {
    let xpic = s.cfg.method.transfer == TransferKind::Xpic;
    if xpic {
        let order = s.cfg.method.xpic_order;
        crate::transfers::xpic::smooth(
            &mut s.particles,
            &s.stencils,
            &s.shape,
            &s.grid,
            order,
            &mut s.xpic,
        );
    }
    let transfer = g2p::Transfer {
        kind: s.cfg.method.transfer,
        flip_alpha: if xpic {
            1.0
        } else {
            s.remedies.flip_fraction(s.dt, s.cfg.method.flip_alpha)
        },
        bilinear_advection: s.implicit()
            && s.cfg.method.projection.advection == crate::config::Advection::Bilinear,
        gradient_enhanced: s.cfg.method.gradient_enhanced,
    };
    g2p::g2p(
        &mut s.particles,
        &s.stencils,
        &s.grid,
        &s.shape,
        &transfer,
        s.dt,
    );
    if !s.remedies.is_empty() {
        s.remedies.after_g2p(&mut step_view!(s));
    }
    s.apply_perturbations();
    lap(&mut s.times.g2p, clock);
}

/// Single stages for `Solver::run_stage` (benchmarks).
pub(crate) fn run_p2g_all(s: &mut Solver, clock: &mut Instant) {
    p2g(s, ALL, clock);
}

pub(crate) fn run_grid(s: &mut Solver, clock: &mut Instant) {
    grid_velocities(s, clock);
    grid_update(s, clock);
}

pub(crate) fn run_g2p(s: &mut Solver, clock: &mut Instant) {
    g2p(s, clock);
}

pub(crate) fn run_stress(s: &mut Solver, clock: &mut Instant) {
    stress(s, StressVelocity::Updated, clock);
}
