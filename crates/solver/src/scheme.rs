//! USF, USL and MUSL as orderings of the same stages.

use crate::config::{ForceKind, QuadratureKind, SchemeKind, TransferKind};
use crate::stage_p2g::{self, Terms};
use crate::stage_times::lap;
use crate::{par, stage_g2p, stage_grid, stage_stress, Solver};
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
            par::keep_warm(|| stage_grid::project_momentum(grid));
            lap(&mut s.times.grid, clock);
            stress(s, StressVelocity::Grid, clock);
        }
    }
}

// The grid stage is serial (a fraction of the particle stages): `keep_warm`
// keeps the pool's other worker awake for the particle stage that follows.
fn grid_velocities(s: &mut Solver, clock: &mut Instant) {
    let grid = &mut s.grid;
    s.ke_grid_p2g = par::keep_warm(|| stage_grid::velocities(grid));
    lap(&mut s.times.grid, clock);
}

fn grid_update(s: &mut Solver, clock: &mut Instant) {
    let (grid, dt) = (&mut s.grid, s.dt);
    // method.min_node_mass is a fraction of a full cell's mass rho0 h^2.
    let guard = stage_grid::MassGuard {
        min_mass: s.cfg.method.min_node_mass * (first_rho0(&s.cfg) * grid.h * grid.h),
        gravity: s.gravity,
    };
    par::keep_warm(|| stage_grid::update(grid, dt, &guard));
    lap(&mut s.times.grid, clock);
}

/// rho0 of the first material: what a "full" node or cell is measured by.
fn first_rho0(cfg: &crate::config::SolverConfig) -> f64 {
    cfg.scene.materials.first().map_or(0.0, |m| m.rho0)
}

fn p2g(s: &mut Solver, terms: Terms, clock: &mut Instant) {
    let inputs = stage_p2g::Inputs {
        particles: &s.particles,
        stencils: &s.stencils,
        shape: &s.shape,
        bins: &s.bins,
        width: s.shape.width(),
        affine: s.cfg.method.transfer == TransferKind::Apic,
        mls: match s.cfg.method.force {
            ForceKind::Mls => s.shape.apic_inverse_inertia(),
            ForceKind::Gradient => None,
        },
        gravity: s.gravity,
    };
    let mixed = terms.force && s.cfg.method.quadrature == QuadratureKind::Mixed;
    let scattered = Terms {
        force: terms.force && !mixed,
        ..terms
    };
    stage_p2g::p2g(&inputs, scattered, &mut s.grid);
    if mixed {
        let rho0 = first_rho0(&s.cfg);
        crate::quadrature_mixed::forces(
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
    let velocity = match which {
        StressVelocity::Grid => &s.grid.vel,
        StressVelocity::Updated => &s.grid.vel_new,
    };
    let inputs = stage_stress::Inputs {
        stencils: &s.stencils,
        shape: &s.shape,
        grid: &s.grid,
        velocity,
        materials: &s.cfg.scene.materials,
        j_update: s.cfg.method.j_update,
        dt: s.dt,
        mls: s.cfg.method.force == ForceKind::Mls,
        f_reset: s.cfg.method.f_reset,
        bulk_damping: s.cfg.method.bulk_damping,
        drop_inverted: s.cfg.scene.on_inversion == crate::config::OnLoss::Delete,
    };
    if s.cfg.method.average_increment {
        // J before this step's update: J-bar averages the increment.
        crate::remedy_volumetric::save_own(&s.particles, &mut s.volumetric);
    }
    s.dissipated += stage_stress::update(&inputs, &mut s.particles, &mut s.partials1);
    volumetric_remedies(s);
    lap(&mut s.times.stress, clock);
}

/// Cell-averaged dilatation or J-bar, volume consistency, then pressure
/// smoothing (each off by default).
fn volumetric_remedies(s: &mut Solver) {
    use crate::remedy_volumetric as rv;
    let m = &s.cfg.method;
    let (ps, scratch) = (&mut s.particles, &mut s.volumetric);
    let averaging = m.cell_dilatation > 0.0 || m.j_bar > 0.0;
    if averaging && !m.carry_averaged_j {
        rv::save_own(ps, scratch);
    }
    if m.cell_dilatation > 0.0 {
        rv::cell_dilatation(ps, &s.grid, m.cell_dilatation, scratch);
    } else if m.j_bar > 0.0 {
        rv::j_bar(ps, &s.stencils, &s.shape, &s.grid, m, scratch);
    }
    let relax = m.volume_relaxation_time > 0.0;
    if relax {
        let blend = (s.dt / m.volume_relaxation_time).min(1.0);
        rv::volume_consistency(ps, &s.stencils, &s.shape, &s.grid, blend, scratch);
    }
    if averaging || relax {
        rv::reevaluate_eos(ps, &s.cfg.scene.materials);
        if !m.carry_averaged_j {
            rv::restore_own(ps, scratch);
        }
    }
    if m.pressure_smoothing {
        rv::smooth_pressure(ps, &s.stencils, &s.shape, &s.grid, scratch);
    }
}

/// This step's FLIP fraction: `flip_alpha`, or 1 - dt / tau under
/// `pic_damping_time = tau`.
fn flip_alpha(m: &crate::config::Method, dt: f64) -> f64 {
    if m.pic_damping_time > 0.0 {
        (1.0 - dt / m.pic_damping_time).max(0.0)
    } else {
        m.flip_alpha
    }
}

fn g2p(s: &mut Solver, clock: &mut Instant) {
    let xpic = s.cfg.method.transfer == TransferKind::Xpic;
    if xpic {
        let order = s.cfg.method.xpic_order;
        crate::transfer_xpic::smooth(
            &mut s.particles,
            &s.stencils,
            &s.shape,
            &s.grid,
            order,
            &mut s.xpic,
        );
    }
    let transfer = stage_g2p::Transfer {
        kind: s.cfg.method.transfer,
        flip_alpha: if xpic {
            1.0
        } else {
            flip_alpha(&s.cfg.method, s.dt)
        },
    };
    stage_g2p::g2p(
        &mut s.particles,
        &s.stencils,
        &s.grid,
        &s.shape,
        &transfer,
        s.dt,
    );
    if s.cfg.method.null_space_filter {
        crate::remedy_null_space::filter(
            &mut s.particles,
            &s.stencils,
            &s.shape,
            &s.grid,
            &mut s.null_space,
        );
    }
    if s.cfg.method.shift_time > 0.0 {
        crate::remedy_shifting::shift(
            &mut s.particles,
            &s.stencils,
            &s.shape,
            &s.grid,
            s.dt / s.cfg.method.shift_time,
            s.cfg.method.shift_surface_share,
            &mut s.shifting,
        );
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
