//! Remedies: treatments that are not the method's own discretisation, each
//! one type in its own file, configured by its own `[method.KEY]` sub-table
//! (absent = off), plugged into the stages through the [`Remedy`] hooks.
//!
//! Adding a remedy: write `remedies/NAME.rs` with a `Settings` type
//! (serde, `Default`) implementing [`Settings`], and add `NAME` to the
//! `registry!` line below. Nothing else reads its settings: the stages call
//! the hooks, the registry validates, names and builds it.
//!
//! Hook order within a step is the registry's order.

mod averaging;
mod registry;
mod stress_work;

pub use averaging::Averager;
pub use registry::Descriptor;

use crate::choices::{ShapeKind, TransferKind};
use crate::config_error::ConfigError;
use crate::grid::Grid;
use crate::material::Material;
use crate::particles::{Mat2, Particles, Vec2};
use crate::shapes::{Shape, Stencil};
use std::sync::Arc;

registry::registry! {
    pic_damping,
    min_node_mass,
    f_reset,
    bulk_damping,
    cell_dilatation,
    j_bar,
    volume_relaxation,
    pressure_smoothing,
    null_space_filter,
    shifting,
    artificial_viscosity,
    grid_damping,
    speed_cap,
}

/// The energy a hook changed in the step it acted on (J per metre of
/// thickness). A hook that changes state books the difference before and
/// after its action (`kinetic`, `stored`, `gravitational`); a hook that
/// changes a stress or a force books the work of that change,
/// dt sum_i df_i . v_i^{n+1/2} (`work`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyChange {
    pub kinetic: f64,
    pub stored: f64,
    pub gravitational: f64,
    pub work: f64,
}

impl EnergyChange {
    pub fn total(&self) -> f64 {
        self.kinetic + self.stored + self.gravitational + self.work
    }
}

/// One remedy's energy change in the last step, with the parts of it that
/// another term of the budget already holds (the monitor books the rest).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RemedyEnergy {
    pub key: &'static str,
    pub change: EnergyChange,
    /// The kinetic change of its after-G2P hooks: the transfer loss (FLIP's
    /// exact update against the particles' velocities) sees it too.
    pub after_g2p_kinetic: f64,
    /// The work of its point rule's extra stress: the stress stage adds it
    /// to `Energy::dissipated` too.
    pub point_work: f64,
}

/// A field a remedy builds the particles' pressure from, for the
/// checkerboard measures (docs/physics.md section 4).
#[derive(Clone, Copy)]
pub enum PressureField<'a> {
    /// Per padded node, the J the particles read their J back from (J-bar).
    NodalJ(&'a Averager),
    /// Per padded node, the pressure the particles read back (pressure
    /// smoothing).
    NodalPressure(&'a Averager),
    /// Per cell of the box (`i + j * cells[0]`), the J every particle of
    /// the cell takes (cell dilatation): total V and total V0.
    CellJ {
        volume: &'a [f64],
        volume0: &'a [f64],
    },
}

impl std::ops::AddAssign for EnergyChange {
    fn add_assign(&mut self, o: Self) {
        self.kinetic += o.kinetic;
        self.stored += o.stored;
        self.gravitational += o.gravitational;
        self.work += o.work;
    }
}

/// What a remedy can run with; every refusal names the remedy's own key.
#[derive(Clone, Copy, Debug)]
pub struct Supports {
    /// Both phases of a mixture (a `[drag]` table).
    pub mixtures: bool,
    /// Materials with a shear modulus (solids).
    pub solids: bool,
    /// Periodic axes (`scene.periodic`).
    pub periodic: bool,
    /// The shape families it works with (empty: all).
    pub shapes: &'static [ShapeKind],
    /// The transfers it works with (empty: all).
    pub transfers: &'static [TransferKind],
}

impl Supports {
    pub const ALL: Supports = Supports {
        mixtures: true,
        solids: true,
        periodic: true,
        shapes: &[],
        transfers: &[],
    };
}

/// A remedy's study-file settings: validated, named and turned into a hook.
pub trait Settings {
    fn descriptor(&self) -> &'static Descriptor;
    fn supports(&self) -> Supports {
        Supports::ALL
    }
    /// Ranges and combinations with the rest of the configuration.
    fn validate(&self, _cfg: &Check) -> Result<(), ConfigError> {
        Ok(())
    }
    /// The hook, with its scratch sized for this grid and these particles.
    fn build(&self, setup: &Setup) -> Box<dyn Remedy>;
}

/// What a remedy is checked against: the rest of the method and the scene.
pub struct Check<'a> {
    pub shape: ShapeKind,
    pub transfer: TransferKind,
    pub flip_alpha: f64,
    pub cfl: f64,
    pub periodic: [bool; 2],
    /// A material has a shear modulus.
    pub solids: bool,
    /// Every remedy of the method (for combinations).
    pub remedies: &'a RemedySettings,
}

/// What a remedy may size its scratch by.
pub struct Setup<'a> {
    pub grid: &'a Grid,
    pub particles: usize,
    /// Particles per cell along each axis (`scene.ppc`).
    pub ppc: usize,
    /// rho0 of the first material: what a full node is measured by.
    pub rho0: f64,
    /// `scene.slab`: the z thickness of the slab, if the scene has one.
    pub slab: Option<f64>,
}

/// The particle side of a step, as a hook sees it.
pub struct Step<'a> {
    pub particles: &'a mut Particles,
    pub stencils: &'a [Stencil],
    pub shape: &'a Shape,
    pub grid: &'a Grid,
    pub materials: &'a [Material],
    pub dt: f64,
    /// |g| (m/s^2), acting in -y.
    pub gravity: f64,
}

/// The grid after its momentum update (v^n in `vel`, v^{n+1} in `vel_new`).
pub struct GridStep<'a> {
    pub grid: &'a mut Grid,
    pub particles: &'a Particles,
    pub stencils: &'a [Stencil],
    pub shape: &'a Shape,
    pub dt: f64,
    pub gravity: Vec2,
}

/// The hooks a remedy implements (each a no-op by default). Each returns the
/// energy it changed (see [`EnergyChange`]).
pub trait Remedy: Send + Sync + RemedyClone {
    fn key(&self) -> &'static str;
    /// Per-particle room for `n` particles (an inflow appends them).
    fn fit_particles(&mut self, _n: usize) {}
    /// After the grid update: v^{n+1} is on the grid, before G2P.
    fn after_grid_update(&mut self, _g: &mut GridStep) -> EnergyChange {
        EnergyChange::default()
    }
    /// The FLIP fraction of this step's FLIP/PIC blend, if the remedy sets it.
    fn flip_fraction(&self, _dt: f64) -> Option<f64> {
        None
    }
    /// After G2P (particle velocities and positions updated).
    fn after_g2p(&mut self, _s: &mut Step) -> EnergyChange {
        EnergyChange::default()
    }
    /// Before the stress update (J, F as of the step start).
    fn before_stress(&mut self, _s: &mut Step) -> EnergyChange {
        EnergyChange::default()
    }
    /// A rule the stress stage applies at every particle, inside its loop.
    fn point_rule(&self) -> Option<Arc<dyn PointRule>> {
        None
    }
    /// After the stress update: returns true when it may have changed J (the
    /// EOS is then evaluated again, once, after every remedy's turn).
    fn after_stress(&mut self, _s: &mut Step) -> (EnergyChange, bool) {
        (EnergyChange::default(), false)
    }
    /// After that re-evaluation (pressure final but for these hooks).
    fn after_pressure(&mut self, _s: &mut Step) -> EnergyChange {
        EnergyChange::default()
    }
    /// The energy change of this step's work of its point rule's extra
    /// stress (`dissipated`: the work the stage summed for this rule).
    fn point_work(&self, _dissipated: f64) -> EnergyChange {
        EnergyChange::default()
    }
    /// The field it builds the particles' pressure from, if it has one
    /// (as of the last step).
    fn pressure_field(&self) -> Option<PressureField<'_>> {
        None
    }
}

/// The most point rules one method may have: the stress stage sums each
/// rule's work apart in a fixed array.
pub const MAX_POINT_RULES: usize = 4;

/// Per-particle rules inside the stress stage's loop (kept there so that
/// their arithmetic and its order are the loop's own).
pub trait PointRule: Send + Sync {
    /// The deformation gradient to keep, given the updated one and J.
    fn deformation(&self, f_next: Mat2, _j_next: f64) -> Mat2 {
        f_next
    }
    /// An extra stress and the power it dissipates per current volume.
    fn extra_stress(
        &self,
        _material: &Material,
        _wave_speed: f64,
        _j: f64,
        _h: f64,
        _d: &Mat2,
    ) -> Option<(Mat2, f64)> {
        None
    }
}

/// `Box<dyn Remedy>` is cloned with its solver.
pub trait RemedyClone {
    fn clone_box(&self) -> Box<dyn Remedy>;
}

impl<T: Remedy + Clone + 'static> RemedyClone for T {
    fn clone_box(&self) -> Box<dyn Remedy> {
        Box::new(self.clone())
    }
}

impl Clone for Box<dyn Remedy> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// The remedies of a run, in registry order, with the energy each changed
/// in the last step.
#[derive(Clone, Default)]
pub struct Remedies {
    pub(crate) list: Vec<Box<dyn Remedy>>,
    pub(crate) energy: Vec<RemedyEnergy>,
    /// The point rules, gathered once, and the remedy each belongs to.
    pub(crate) points: Vec<Arc<dyn PointRule>>,
    point_owner: Vec<usize>,
}

impl Remedies {
    pub fn build(settings: &RemedySettings, setup: &Setup) -> Self {
        let list: Vec<Box<dyn Remedy>> = settings.active().iter().map(|s| s.build(setup)).collect();
        let (point_owner, points): (Vec<usize>, Vec<Arc<dyn PointRule>>) = list
            .iter()
            .enumerate()
            .filter_map(|(i, r)| Some((i, r.point_rule()?)))
            .unzip();
        debug_assert!(
            points.len() <= MAX_POINT_RULES,
            "more point rules than the stress stage books apart"
        );
        Remedies {
            energy: list
                .iter()
                .map(|r| RemedyEnergy {
                    key: r.key(),
                    ..RemedyEnergy::default()
                })
                .collect(),
            list,
            points,
            point_owner,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    pub(crate) fn begin_step(&mut self) {
        for e in &mut self.energy {
            *e = RemedyEnergy {
                key: e.key,
                ..RemedyEnergy::default()
            };
        }
    }

    pub(crate) fn fit_particles(&mut self, n: usize) {
        for r in &mut self.list {
            r.fit_particles(n);
        }
    }

    /// Each remedy's key and the energy it changed in the last step.
    pub fn energy(&self) -> impl Iterator<Item = (&'static str, EnergyChange)> + '_ {
        self.energy.iter().map(|e| (e.key, e.change))
    }

    /// Each remedy's energy change in the last step, with the parts other
    /// budget terms hold, in registry order.
    pub fn energy_parts(&self) -> &[RemedyEnergy] {
        &self.energy
    }

    /// Each remedy's pressure field, where it has one.
    pub fn pressure_fields(&self) -> impl Iterator<Item = (&'static str, PressureField<'_>)> + '_ {
        self.list
            .iter()
            .filter_map(|r| Some((r.key(), r.pressure_field()?)))
    }

    pub(crate) fn after_grid_update(&mut self, g: &mut GridStep) {
        for (r, e) in self.list.iter_mut().zip(&mut self.energy) {
            e.change += r.after_grid_update(g);
        }
    }

    /// The blend a remedy sets, else `default`.
    pub(crate) fn flip_fraction(&self, dt: f64, default: f64) -> f64 {
        self.list
            .iter()
            .find_map(|r| r.flip_fraction(dt))
            .unwrap_or(default)
    }

    pub(crate) fn after_g2p(&mut self, s: &mut Step) {
        for (r, e) in self.list.iter_mut().zip(&mut self.energy) {
            let change = r.after_g2p(s);
            e.after_g2p_kinetic += change.kinetic;
            e.change += change;
        }
    }

    pub(crate) fn before_stress(&mut self, s: &mut Step) {
        for (r, e) in self.list.iter_mut().zip(&mut self.energy) {
            e.change += r.before_stress(s);
        }
    }

    /// Each point rule's share of the stress stage's dissipated work.
    pub(crate) fn book_point_work(&mut self, work: &[f64]) {
        for (&owner, w) in self.point_owner.iter().zip(work) {
            let change = self.list[owner].point_work(*w);
            let e = &mut self.energy[owner];
            e.point_work += change.total();
            e.change += change;
        }
    }

    /// The hooks after the stress update, the EOS once again if one of them
    /// changed J, then the hooks after the pressure.
    pub(crate) fn after_stress(&mut self, s: &mut Step) {
        let mut j_changed = false;
        for (r, e) in self.list.iter_mut().zip(&mut self.energy) {
            let (change, changed) = r.after_stress(s);
            e.change += change;
            j_changed |= changed;
        }
        if j_changed {
            reevaluate_eos(s.particles, s.materials);
        }
        for (r, e) in self.list.iter_mut().zip(&mut self.energy) {
            e.change += r.after_pressure(s);
        }
    }
}

/// Pressure, wave speed, stored energy and stress again after J changed.
pub fn reevaluate_eos(ps: &mut Particles, materials: &[Material]) {
    for p in 0..ps.len() {
        let m = &materials[ps.material[p] as usize];
        let j = ps.j[p];
        let state = m.eos(j);
        let p_new = m.cut(state.pressure);
        ps.stress[p] += Mat2::identity() * (ps.pressure[p] - p_new);
        ps.pressure[p] = p_new;
        ps.wave_speed[p] = m.wave_speed_of(&state, j);
        ps.stored_energy[p] = ps.vol0[p] * m.energy_of(j, &state);
    }
}

/// V0 U(J) of one particle (its stored energy at J).
#[inline]
pub fn stored_energy_at(ps: &Particles, materials: &[Material], p: usize, j: f64) -> f64 {
    ps.vol0[p] * materials[ps.material[p] as usize].stored(j)
}

/// sum 1/2 m |v|^2.
pub fn kinetic_energy(ps: &Particles) -> f64 {
    ps.mass
        .iter()
        .zip(&ps.v)
        .map(|(m, v)| 0.5 * m * v.norm_squared())
        .sum()
}

/// A range check by study key: `lo < v <= hi` (and finite).
pub(crate) fn positive_up_to(v: f64, hi: f64, key: &str) -> Result<(), ConfigError> {
    if v.is_finite() && v > 0.0 && v <= hi {
        Ok(())
    } else {
        Err(ConfigError {
            key: key.into(),
            message: format!("{v} is out of range (allowed > 0 and <= {hi})"),
        })
    }
}
