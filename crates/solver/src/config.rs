//! Plain-data description of a scene and a method. The study crate fills these
//! from TOML; the solver only reads them. The enums live in `choices`, the
//! material in `material`.

pub use crate::choices::*;

pub use crate::config_error::ConfigError;
use crate::config_error::{check, ordered_rect, within};
pub use crate::material::Material;
use crate::perturb::Perturb;
use crate::remedies::RemedySettings;
use serde::{Deserialize, Serialize};

/// A `[[scene.body]]`: a rectangle of one material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// [x0, y0, x1, y1] in metres.
    pub rect: [f64; 4],
    /// Name of its material; may be left empty when the scene has one material.
    #[serde(default)]
    pub material: String,
    /// Initial velocity (m/s).
    #[serde(default)]
    pub velocity: [f64; 2],
    /// The share of the mixture's volume this body's phase takes (its volume
    /// fraction n, 0 < n <= 1; docs/physics.md section 6): each particle
    /// carries n times its lattice volume and mass, so rho0 stays the true
    /// density and n rho0 is the partial one. 1 for a single phase.
    #[serde(default = "Body::full", skip_serializing_if = "Body::is_full")]
    pub fraction: f64,
    /// Which phase of a mixture the body belongs to (studies with a `[drag]`
    /// table); None in a single-phase scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phase: Option<Phase>,
    /// An initial flow over the body, added to `velocity` once the initial
    /// state stands (docs/physics.md section 7).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flow: Option<crate::flows::Flow>,
}

/// The two phases of a mixture (docs/physics.md section 6): the solid
/// skeleton is phase 0, the pore fluid phase 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    Solid,
    Fluid,
}

impl Phase {
    pub const ALL: [Phase; 2] = [Phase::Solid, Phase::Fluid];

    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            Phase::Solid => "solid",
            Phase::Fluid => "fluid",
        }
    }
}

impl Body {
    fn full() -> f64 {
        1.0
    }

    fn is_full(fraction: &f64) -> bool {
        *fraction == 1.0
    }
}

/// The `[scene]` table. Defaults: the dam-break tank of docs/physics.md section 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Scene {
    /// Lower-left corner of the box (metres).
    pub origin: [f64; 2],
    /// Box width and height (metres); must be whole cells.
    #[serde(rename = "box")]
    pub size: [f64; 2],
    /// Cell size h (metres).
    pub cell: f64,
    /// Particles per cell along each axis.
    pub ppc: usize,
    /// Simulated time (s).
    pub t_end: f64,
    /// Magnitude of gravity (m/s^2), acting in -y.
    pub gravity: f64,
    pub initial: InitialState,
    /// Periodic instead of symmetry-plane walls, per axis.
    pub periodic: [bool; 2],
    /// Ensemble members: initial positions moved by a seeded uniform offset
    /// of at most `jitter` h per axis (0 = none).
    pub jitter: f64,
    /// Seed of the jitter (one per ensemble member).
    pub seed: u64,
    /// A particle outside the box (non-periodic axes): stop the run or delete it.
    pub on_escape: OnLoss,
    /// A particle with J <= 0 or det F <= 0: stop the run or delete it.
    pub on_inversion: OnLoss,
    /// A particle whose position, velocity, J, pressure, stress or stored
    /// energy is not a finite number: stop the run, or delete it (Uintah
    /// goes on: its relocation drops a position no patch holds, and its
    /// step skips a NaN speed).
    pub on_nonfinite: OnLoss,
    /// Fraction of the initial mass that deleted particles may take before
    /// the run counts as blown up (the harness's convention, not Uintah's).
    pub lost_mass_limit: f64,
    /// A particle whose J exceeds this counts as degenerate, like an
    /// inverted one (`on_inversion`): Uintah's Water model deletes J > 1e5.
    /// None: no upper limit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_j: Option<f64>,
    /// Walls with zero tangential grid velocity (the others are free-slip
    /// symmetry planes), e.g. `no_slip = ["floor"]`.
    pub no_slip: Vec<Wall>,
    /// The thickness dz (m) of the one-cell slab a 3D code such as Uintah
    /// runs this plane-strain scene in: its z axis joins the per-axis step
    /// (CFL dz / max c) and Uintah's artificial viscosity's length
    /// (2 h + dz) / 3. None: no z axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slab: Option<f64>,
    /// The ghost nodes beyond a wall: folded onto their partners, or
    /// discarded and overwritten (Uintah).
    #[serde(skip_serializing_if = "WallGhosts::is_fold")]
    pub wall_ghosts: WallGhosts,
    #[serde(rename = "body")]
    pub bodies: Vec<Body>,
    /// Filled from the study's `[materials]` tables, in file order.
    #[serde(skip)]
    pub materials: Vec<Material>,
}

impl Default for Scene {
    /// The dam-break tank (0.8 x 0.6 m, h = 1 cm, 2 x 2 ppc, 5 s), still empty.
    fn default() -> Self {
        Scene {
            origin: [0.0, 0.0],
            size: [0.8, 0.6],
            cell: 0.01,
            ppc: 2,
            t_end: 5.0,
            gravity: 9.81,
            initial: InitialState::ZeroStress,
            periodic: [false, false],
            jitter: 0.0,
            seed: 0,
            on_escape: OnLoss::Stop,
            on_inversion: OnLoss::Stop,
            on_nonfinite: OnLoss::Stop,
            lost_mass_limit: 0.1,
            max_j: None,
            no_slip: vec![],
            slab: None,
            wall_ghosts: WallGhosts::Fold,
            bodies: vec![],
            materials: vec![],
        }
    }
}

impl Scene {
    /// No-slip flags per [axis][low side, high side].
    pub fn no_slip_mask(&self) -> [[bool; 2]; 2] {
        Wall::mask(&self.no_slip)
    }

    /// docs/physics.md section 1: 0.8 x 0.6 box, 0.2 x 0.4 water column, h = 1 cm, 2 x 2 ppc.
    pub fn dam_break(material: Material) -> Self {
        Scene {
            bodies: vec![Body {
                rect: [0.0, 0.0, 0.2, 0.4],
                material: material.name.clone(),
                velocity: [0.0, 0.0],
                fraction: 1.0,
                phase: None,
                flow: None,
            }],
            materials: vec![material],
            ..Scene::default()
        }
    }

    /// The bodies' extent in x, [left, right]: where `hydrostatic_gate` holds them.
    pub fn gated_span(&self) -> [f64; 2] {
        self.bodies
            .iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY], |[a, b], body| {
                [a.min(body.rect[0]), b.max(body.rect[2])]
            })
    }

    /// The box cut to the gates: walls at the bodies' left and right edges.
    pub fn gated(&self) -> Scene {
        let [x0, x1] = self.gated_span();
        let mut held = self.clone();
        held.origin[0] = x0;
        held.size[0] = ((x1 - x0) / self.cell).round() * self.cell;
        held
    }

    /// Number of cells along each axis.
    pub fn cells(&self) -> [usize; 2] {
        [
            (self.size[0] / self.cell).round() as usize,
            (self.size[1] / self.cell).round() as usize,
        ]
    }

    /// Index of a body's material: by name, or the only one when the name is empty.
    pub fn material_index(&self, body: &Body) -> Option<usize> {
        if body.material.is_empty() && self.materials.len() == 1 {
            return Some(0);
        }
        self.materials.iter().position(|m| m.name == body.material)
    }
}

/// The `[method]` table: every suspect choice. Defaults: the problem
/// statement's baseline (linear, FLIP, USF, fixed dt, CFL 0.2, det J).
// deny_unknown_fields does not combine with flatten: `RemedySettings` refuses
// the keys that are neither a field here nor a remedy.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Method {
    pub shape: ShapeKind,
    pub transfer: TransferKind,
    /// FLIP fraction of the FLIP/PIC blend (1 = pure FLIP).
    pub flip_alpha: f64,
    /// Uintah's gradient-enhanced velocity projection
    /// (`UseGradientEnhancedVelocityProjection`): FLIP's P2G carries
    /// m (v_p + L_p (x_i - x_p)), with L_p the velocity gradient of the
    /// particle's last G2P; the G2P stays FLIP. FLIP, USL and explicit
    /// only. Left out of the serialisation when off, so that the methods
    /// written before it keep their identity.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub gradient_enhanced: bool,
    pub scheme: SchemeKind,
    /// Courant number of the time step.
    pub cfl: f64,
    pub dt: DtMode,
    /// Use this time step (s) instead of the CFL one (benchmarks); absent = CFL.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_value: Option<f64>,
    /// A floor under the CFL step (s): a step that falls below it is raised
    /// to it, as Uintah's `delt_min` does, past the CFL limit if need be
    /// (docs/findings/four_behaviours_candidates.md); absent = none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_min: Option<f64>,
    pub j_update: JUpdate,
    /// Force and velocity-gradient discretisation (`gradient` or `mls`).
    pub force: ForceKind,
    /// Where the internal force is integrated: `particles` or `mixed`
    /// (fixed points in the cells full of material).
    pub quadrature: QuadratureKind,
    /// The order m of `transfer = "xpic"` (1 = PIC).
    pub xpic_order: u32,
    /// `explicit` (the default) or `pressure_implicit`.
    #[serde(skip_serializing_if = "is_explicit")]
    pub formulation: Formulation,
    /// `[method.projection]`: the pressure-implicit formulation's settings.
    #[serde(skip_serializing_if = "is_default_projection")]
    pub projection: ProjectionSettings,
    /// The remedies, each its own `[method.KEY]` sub-table (absent = off;
    /// `remedies/`). It also refuses every key that is neither.
    #[serde(flatten)]
    pub remedies: RemedySettings,
}

impl Default for Method {
    fn default() -> Self {
        Method {
            shape: ShapeKind::Linear,
            transfer: TransferKind::Flip,
            flip_alpha: 1.0,
            gradient_enhanced: false,
            scheme: SchemeKind::Usf,
            cfl: 0.2,
            dt: DtMode::Fixed,
            dt_value: None,
            dt_min: None,
            j_update: JUpdate::Det,
            force: ForceKind::Gradient,
            quadrature: QuadratureKind::Particles,
            xpic_order: 2,
            formulation: Formulation::Explicit,
            projection: ProjectionSettings::default(),
            remedies: RemedySettings::default(),
        }
    }
}

/// The gradient-enhanced projection as Uintah runs it: FLIP, USL (its L
/// is the one the F update used only there), explicit.
fn validate_gradient_enhanced(m: &Method) -> Result<(), ConfigError> {
    if !m.gradient_enhanced {
        return Ok(());
    }
    check(
        m.transfer == TransferKind::Flip
            && m.scheme == SchemeKind::Usl
            && m.formulation == Formulation::Explicit,
        "method.gradient_enhanced",
        format!(
            "true needs method.transfer = \"flip\", method.scheme = \"usl\" and the explicit formulation (got {:?}, {:?}, {:?})",
            m.transfer, m.scheme, m.formulation
        ),
    )
}

fn is_explicit(f: &Formulation) -> bool {
    *f == Formulation::Explicit
}

fn is_default_projection(p: &ProjectionSettings) -> bool {
    *p == ProjectionSettings::default()
}

/// `[method.projection]`: the controls of the pressure-implicit step
/// (docs/physics.md section 8).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProjectionSettings {
    /// Where the velocities live: on the nodes with cell pressures (Q1-P0,
    /// held by the controls below) or on the cell faces (MAC, inf-sup
    /// stable; it reads none of hourglass, checkerboard and air_nodes, its
    /// free surface is "cell" or "ghost", and its drift correction is by
    /// position).
    pub scheme: ProjectionScheme,
    /// Share of each fluid cell's hourglass velocity (the nodal mode the
    /// cell divergence cannot see) removed per step, 0 ..= 0.25.
    pub hourglass: f64,
    /// Weight of the cell pressure's checkerboard control (the 2 x 2
    /// alternating sums around each node, against the 1 / rho0 scale of
    /// the operator), 0 ..= 16.
    pub checkerboard: f64,
    /// Share of the grid packing's error (packing J - 1 in the cells whose
    /// nodes are full) corrected per step, 0 ..= 1.
    pub drift: f64,
    /// How the drift is corrected: by moving the particles (a second solve
    /// of the same operator for a displacement) or by a divergence target
    /// in the velocity solve (which the particles then carry as flow).
    pub drift_correction: DriftCorrection,
    /// Relative residual at which the drift correction by position's
    /// conjugate gradient stops (it corrects a share of a smoothed error).
    pub drift_tolerance: f64,
    /// The packing error is read only in cells whose neighbours within
    /// this many cells are all fluid (0: wherever the four corners are
    /// full): near the surface the nodal masses follow the surface's
    /// height, so a wave reads as packing error there.
    pub drift_depth: u32,
    /// The velocity field the particles move with: the bilinear element's
    /// (on the collocated scheme its cell-integrated divergence is the
    /// solved D u; on the staggered one it is each component linear
    /// between its nearest faces, exact for an affine field) or the run's
    /// shape functions'.
    pub advection: Advection,
    /// How the particles' positions step through that velocity field
    /// (staggered scheme only): one Euler step, or the midpoint rule.
    pub advection_step: AdvectionStep,
    /// A cell without particles inside the water (staggered scheme only):
    /// air, at p = 0, or fluid, with a row in the solve, so that a hole
    /// the particles' sampling opens is not a free surface the water falls
    /// into (`Holes` says which cells count).
    pub holes: Holes,
    /// The pressure step's weight on the new time level (staggered scheme
    /// only), 0.5 ..= 1: the momentum takes theta p^{n+1} + (1 - theta)
    /// p^n and J the same mix of D u. 1 is backward Euler, which damps
    /// sound by a factor 1 / sqrt(1 + (omega dt)^2) a step; 0.5 is the
    /// trapezoidal rule, which keeps linear sound's energy and damps no
    /// mode at all (docs/physics.md section 8b). At K = inf there is no
    /// sound and the step is backward Euler whatever theta.
    pub theta: f64,
    /// The step's gravity limit dt <= gravity_cfl sqrt(h / g), where the
    /// flow is slow (a slosh, a column settling), 1e-3 ..= 1; None: the
    /// method's cfl.
    /// Its own knob because the gravity waves' time error drifts the
    /// packing where the flow's limit does not bind (docs/findings/
    /// projection_mac.md, "The gravity limit of the step").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gravity_cfl: Option<f64>,
    /// Where the free surface's p = 0 sits: at the air cells' centres, or
    /// inside the cell where the grid's fluid fraction crosses a half (on
    /// the staggered scheme the surface then moves with the water instead
    /// of jumping a cell when a particle crosses a cell's edge).
    pub free_surface: FreeSurface,
    /// How a ghost surface reads where p = 0 sits between a fluid cell and
    /// its air neighbour from their fluid fractions.
    #[serde(skip_serializing_if = "SurfaceLevel::is_fraction")]
    pub surface_level: SurfaceLevel,
    /// The least share theta of the way to an air cell's centre at which
    /// a ghost surface may sit, 0.001 ..= 0.5: the surface face's pressure
    /// force takes 1 / theta, so a surface near a fluid cell's centre
    /// (a thin sheet) multiplies it up to 1 / this.
    #[serde(skip_serializing_if = "is_default_surface_floor")]
    pub min_surface_share: f64,
    /// What else bounds theta from below on the staggered scheme's faces
    /// (a ghost surface's only).
    #[serde(skip_serializing_if = "ShareFloor::is_fixed")]
    pub share_floor: ShareFloor,
    /// What the nodes beyond the fluid cells (which take their fluid
    /// neighbours' velocity after the solve) bring to it.
    pub air_nodes: AirNodes,
    /// A node lighter than this share of rho0 h^2 takes that mass in the
    /// pressure operator and its velocity correction (free-surface nodes).
    pub light_node_share: f64,
    /// The mass each face's pressure gradient divides by (staggered scheme
    /// only): the particles' mass on it, or the material's rho0 h^2 / J.
    pub face_density: FaceDensity,
    /// Relative residual |b - A p| / |b| at which the conjugate gradient stops.
    pub tolerance: f64,
    pub max_iterations: u32,
    /// The conjugate gradient's preconditioner.
    pub preconditioner: Preconditioner,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProjectionScheme {
    /// Bilinear nodal velocities, cell pressures (Q1-P0).
    Collocated,
    /// Staggered: each component on the faces normal to it.
    Mac,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DriftCorrection {
    /// Particle positions only: velocities, J and the stored energy are
    /// untouched; the gravitational energy it changes is booked.
    Position,
    /// A divergence target r in the velocity solve.
    Velocity,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Advection {
    /// x += dt sum N^Q1_i(x) v_i over the particle's cell corners.
    Bilinear,
    /// x += dt sum N_ip v_i with the run's shapes (B-spline tails included).
    Shape,
    /// Staggered only: each component linear between the two faces of the
    /// particle's cell, constant along them (the lowest Raviart-Thomas
    /// element), divergence-free at every point of a balanced cell.
    Flux,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Holes {
    /// p = 0 in the hole, as at the free surface.
    Air,
    /// The hole is a fluid cell of the solve (its J read as 1); a wall
    /// counts as a side that holds particles.
    Fluid,
    /// As `Fluid`, and a cell that was fluid at the last step stays fluid
    /// when its particles leave it (its J read as 1) while its corners'
    /// B-spline mass fills at least half of it: a pocket the particles'
    /// sampling opens inside the water keeps its volume; air the water
    /// closes in (never fluid) is still air.
    Kept,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AdvectionStep {
    /// x += dt v(x).
    Euler,
    /// x += dt v(x + dt v(x) / 2): second order in dt along a path.
    Midpoint,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FreeSurface {
    /// A cell holding a particle is fluid; p = 0 at the air cells' centres.
    Cell,
    /// A cell is fluid where the grid's fluid fraction is at least a half;
    /// p = 0 where that fraction, interpolated between a fluid cell and
    /// its air neighbour, crosses a half (ghost fluid: the corner's
    /// pressure force scaled by 1 / theta). The divergence is unweighted,
    /// so the projection is oblique in the nodal masses and can add
    /// kinetic energy.
    Ghost,
    /// The same surface with the divergence weighted as the force: the
    /// projection is orthogonal in the nodal masses and never adds kinetic
    /// energy; the constraint is then a weighted divergence at the surface.
    GhostOrthogonal,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceLevel {
    /// The fraction less a half, interpolated linearly between the two
    /// centres: the fraction is a smooth step (the kernels smear the
    /// surface), so the surface placed moves 9 % less than the water near
    /// a cell's edge and up to 20 % more near a centre (quadratic
    /// B-splines).
    Fraction,
    /// Each fraction mapped to the depth at which a cell below a flat
    /// surface reads it under the run's kernel, then interpolated: exact
    /// for a flat surface along a grid axis at any height in its cell.
    Distance,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShareFloor {
    /// `min_surface_share` alone. The ghost surface's projection is
    /// orthogonal in the faces' masses theta rho0 h^2 (its gradient takes
    /// 1 / theta, its divergence does not), so where a face carries more
    /// of the particles' mass than that (a thin sheet, a corner) the
    /// projection can add kinetic energy.
    Fixed,
    /// Also the share at which a flat surface would give the face its own
    /// mass, less the two readings' spread on a flat surface (0.05 of a
    /// cell): theta cannot place the surface nearer the fluid cell's
    /// centre than the face's mass allows.
    FaceMass,
}

impl ShareFloor {
    fn is_fixed(&self) -> bool {
        *self == ShareFloor::Fixed
    }
}

/// `min_surface_share`'s default.
const DEFAULT_SURFACE_FLOOR: f64 = 0.05;

fn is_default_surface_floor(floor: &f64) -> bool {
    *floor == DEFAULT_SURFACE_FLOOR
}

impl SurfaceLevel {
    fn is_fraction(&self) -> bool {
        *self == SurfaceLevel::Fraction
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AirNodes {
    /// Their velocity is a kinematic constraint (the mean of their fluid
    /// neighbours'), so their mass and u* momentum join those neighbours'
    /// before the solve, in equal shares: the weight of the material the
    /// B-spline carries beyond the fluid cells rests on the pressure.
    Slaved,
    /// Their u* is overwritten after the solve: their weight is lost
    /// (the surface's restoring force is short by the share the stencils
    /// carry beyond the fluid cells).
    Overwritten,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaceDensity {
    /// The particles' mass on the face (with the air faces' shares): where
    /// the particles pack unevenly, the projection reads the packing as
    /// density, and gravity turns it over (denser packing sinks).
    Particles,
    /// rho0 h^2 / J on every face whose two cells and their neighbours
    /// are fluid (J the cells' particle volumes over their rest volumes);
    /// nearer the surface the particles' mass, capped there. The fluid's
    /// density then follows its compression, not its packing.
    Material,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preconditioner {
    /// The diagonal.
    Jacobi,
    /// Incomplete Cholesky on the 3 x 3 pattern, the matrix read by nine
    /// probes (Jacobi on a periodic axis whose cell count is not a multiple of 3).
    Ic0,
    /// Modified incomplete Cholesky (the dropped fill moved onto the
    /// diagonals, keeping the row sums), on the same pattern and probes.
    Mic0,
}

impl Default for ProjectionSettings {
    fn default() -> Self {
        ProjectionSettings {
            scheme: ProjectionScheme::Collocated,
            hourglass: 0.05,
            checkerboard: 1.5,
            drift: 0.3,
            drift_correction: DriftCorrection::Position,
            drift_tolerance: 1e-6,
            drift_depth: 0,
            advection: Advection::Shape,
            advection_step: AdvectionStep::Euler,
            holes: Holes::Air,
            theta: 1.0,
            gravity_cfl: None,
            free_surface: FreeSurface::Cell,
            surface_level: SurfaceLevel::Fraction,
            min_surface_share: DEFAULT_SURFACE_FLOOR,
            share_floor: ShareFloor::Fixed,
            air_nodes: AirNodes::Slaved,
            light_node_share: 0.01,
            face_density: FaceDensity::Particles,
            tolerance: 1e-8,
            max_iterations: 4000,
            preconditioner: Preconditioner::Mic0,
        }
    }
}

impl Method {
    /// The problem statement's baseline (the defaults).
    pub fn baseline() -> Self {
        Method::default()
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverConfig {
    pub scene: Scene,
    pub method: Method,
    pub perturb: Vec<Perturb>,
}

/// The `[method.projection]` numbers' ranges.
fn validate_projection_ranges(p: &ProjectionSettings) -> Result<(), ConfigError> {
    within(p.hourglass, 0.0, 0.25, "method.projection.hourglass")?;
    within(p.checkerboard, 0.0, 16.0, "method.projection.checkerboard")?;
    within(p.drift, 0.0, 1.0, "method.projection.drift")?;
    within(p.theta, 0.5, 1.0, "method.projection.theta")?;
    within(
        p.min_surface_share,
        1e-3,
        0.5,
        "method.projection.min_surface_share",
    )?;
    if let Some(c) = p.gravity_cfl {
        within(c, 1e-3, 1.0, "method.projection.gravity_cfl")?;
    }
    within(
        p.drift_depth as f64,
        0.0,
        8.0,
        "method.projection.drift_depth",
    )?;
    within(
        p.light_node_share,
        1e-6,
        1.0,
        "method.projection.light_node_share",
    )?;
    within(p.tolerance, 1e-14, 1e-2, "method.projection.tolerance")?;
    within(
        p.drift_tolerance,
        1e-14,
        1e-2,
        "method.projection.drift_tolerance",
    )?;
    within(
        p.max_iterations as f64,
        1.0,
        1e6,
        "method.projection.max_iterations",
    )?;
    Ok(())
}

impl SolverConfig {
    /// rho0 of the first material: what a "full" node or cell is measured by.
    pub fn first_rho0(&self) -> f64 {
        self.scene.materials.first().map_or(0.0, |m| m.rho0)
    }

    /// The remedies' hooks for this configuration, sized for `grid` and `particles`.
    pub(crate) fn build_remedies(
        &self,
        grid: &crate::grid::Grid,
        particles: usize,
    ) -> crate::remedies::Remedies {
        let setup = crate::remedies::Setup {
            grid,
            particles,
            ppc: self.scene.ppc,
            rho0: self.first_rho0(),
            slab: self.scene.slab,
        };
        crate::remedies::Remedies::build(&self.method.remedies, &setup)
    }

    /// The dam break the benchmarks time (`kick bench`, criterion): power law
    /// gamma 7 at K = 150 kPa, the baseline method with `shape` and `transfer`.
    pub fn benchmark_dam_break(shape: ShapeKind, transfer: TransferKind, cell: f64) -> Self {
        let mut scene = Scene::dam_break(Material::new(1.5e5));
        scene.cell = cell;
        let method = Method {
            shape,
            transfer,
            ..Method::baseline()
        };
        SolverConfig {
            scene,
            method,
            perturb: vec![],
        }
    }

    /// Every range check, named by study key: the one validation pass.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.validate_materials()?;
        self.validate_scene()?;
        let m = &self.method;
        within(m.flip_alpha, 0.0, 1.0, "method.flip_alpha")?;
        validate_gradient_enhanced(m)?;
        within(m.cfl, 1e-4, 1.0, "method.cfl")?;
        if let Some(dt) = m.dt_value {
            within(dt, 1e-12, 1.0, "method.dt_value")?;
        }
        if let Some(dt) = m.dt_min {
            within(dt, 1e-12, 1.0, "method.dt_min")?;
            check(
                m.formulation == Formulation::Explicit,
                "method.dt_min",
                "applies to the explicit formulation only (the pressure-implicit step follows the flow)",
            )?;
        }
        within(m.xpic_order as f64, 1.0, 16.0, "method.xpic_order")?;
        if m.force == ForceKind::Mls {
            // D = sum N (x_i - x_p)(x_i - x_p)^T is singular at the nodes for linear and uGIMP shapes.
            check(
                matches!(m.shape, ShapeKind::Bspline2 | ShapeKind::Bspline3)
                    && m.transfer == TransferKind::Apic,
                "method.force",
                format!(
                    "\"mls\" needs method.shape = \"bspline2\" | \"bspline3\" and method.transfer = \"apic\" (got {:?}, {:?})",
                    m.shape, m.transfer
                ),
            )?;
        }
        if m.quadrature == QuadratureKind::Mixed {
            check(
                matches!(
                    m.shape,
                    ShapeKind::Linear | ShapeKind::Bspline2 | ShapeKind::Bspline3
                ) && m.force == ForceKind::Gradient,
                "method.quadrature",
                format!(
                    "\"mixed\" needs method.shape = \"linear\" | \"bspline2\" | \"bspline3\" (GIMP's kernels belong to the particles, not to a point) and method.force = \"gradient\" (got {:?}, {:?})",
                    m.shape, m.force
                ),
            )?;
            check(
                self.scene.materials.len() == 1,
                "method.quadrature",
                format!(
                    "\"mixed\" needs a single material (a full cell is judged by rho0; got {})",
                    self.scene.materials.len()
                ),
            )?;
        }
        self.validate_cpdi()?;
        m.remedies.validate(&crate::remedies::Check {
            shape: m.shape,
            transfer: m.transfer,
            flip_alpha: m.flip_alpha,
            cfl: m.cfl,
            periodic: self.scene.periodic,
            solids: self
                .scene
                .materials
                .iter()
                .any(|mat| mat.shear_modulus > 0.0),
            remedies: &m.remedies,
        })?;
        if m.formulation == Formulation::PressureImplicit {
            self.validate_pressure_implicit()?;
        }
        for (i, p) in self.perturb.iter().enumerate() {
            p.validate(i, self.scene.cells())?;
        }
        Ok(())
    }

    /// CPDI's weights are not a tensor product: the paths that read
    /// per-axis weights refuse it (the remedies by their `Supports`).
    fn validate_cpdi(&self) -> Result<(), ConfigError> {
        let m = &self.method;
        if m.shape != ShapeKind::Cpdi {
            return Ok(());
        }
        check(
            m.formulation == Formulation::Explicit,
            "method.formulation",
            "\"pressure_implicit\" reads per-axis weights; method.shape = \"cpdi\" needs \"explicit\"",
        )?;
        check(
            m.transfer != TransferKind::Xpic,
            "method.transfer",
            "\"xpic\" reads per-axis weights; method.shape = \"cpdi\" needs \"pic\" | \"flip\" | \"apic\"",
        )
    }

    fn validate_scene(&self) -> Result<(), ConfigError> {
        let s = &self.scene;
        within(s.cell, 1e-5, 10.0, "scene.cell")?;
        for a in 0..2 {
            let n = s.size[a] / s.cell;
            check(
                s.size[a] > 0.0 && (n - n.round()).abs() < 1e-6 && (2.0..=1e5).contains(&n.round()),
                "scene.box",
                format!(
                    "axis {a}: {} m is not a whole number (2 ..= 100000) of {} m cells",
                    s.size[a], s.cell
                ),
            )?;
        }
        check(
            s.origin.iter().all(|v| v.is_finite()),
            "scene.origin",
            "must be finite",
        )?;
        within(s.ppc as f64, 1.0, 8.0, "scene.ppc")?;
        within(s.t_end, 1e-9, 1e4, "scene.t_end")?;
        within(s.gravity, 0.0, 1e4, "scene.gravity")?;
        within(s.jitter, 0.0, 1e-3, "scene.jitter")?;
        within(s.lost_mass_limit, 1e-9, 1.0, "scene.lost_mass_limit")?;
        check(
            s.wall_ghosts == WallGhosts::Fold
                || self.method.formulation != Formulation::PressureImplicit,
            "scene.wall_ghosts",
            "method.formulation = \"pressure_implicit\" folds its walls' images (its operator is built on them): use \"fold\"",
        )?;
        check(
            s.on_escape != OnLoss::Keep,
            "scene.on_escape",
            "\"keep\" is for on_inversion only (a particle outside the box has no grid); allowed: \"stop\", \"delete\"",
        )?;
        check(
            s.on_nonfinite != OnLoss::Keep,
            "scene.on_nonfinite",
            "\"keep\" is for on_inversion only (a non-finite particle poisons its nodes); allowed: \"stop\", \"delete\"",
        )?;
        if let Some(dz) = s.slab {
            within(dz, 1e-6, 10.0, "scene.slab")?;
        }
        if let Some(j) = s.max_j {
            within(j, 1.0 + 1e-9, 1e300, "scene.max_j")?;
        }
        for w in &s.no_slip {
            check(
                !s.periodic[w.axis()],
                "scene.no_slip",
                format!("{w:?} is on a periodic axis (scene.periodic): there is no wall there"),
            )?;
        }
        check(
            !s.bodies.is_empty(),
            "scene.body",
            "at least one [[scene.body]] is required",
        )?;
        for (i, b) in s.bodies.iter().enumerate() {
            self.validate_body(i, b)?;
        }
        if s.initial == InitialState::HydrostaticGate {
            self.validate_gates()?;
        }
        Ok(())
    }

    /// Body `i`: a rectangle inside the box, a fraction in (0, 1], a known
    /// material, a finite velocity and a consistent initial flow.
    fn validate_body(&self, i: usize, b: &Body) -> Result<(), ConfigError> {
        let s = &self.scene;
        let key = format!("scene.body[{i}].rect");
        ordered_rect(&b.rect, &key)?;
        check(
            b.rect[0] >= s.origin[0] - 1e-12
                && b.rect[1] >= s.origin[1] - 1e-12
                && b.rect[2] <= s.origin[0] + s.size[0] + 1e-12
                && b.rect[3] <= s.origin[1] + s.size[1] + 1e-12,
            &key,
            "must lie inside the box",
        )?;
        check(
            b.fraction > 0.0 && b.fraction <= 1.0,
            &format!("scene.body[{i}].fraction"),
            format!("{} is outside (0, 1]", b.fraction),
        )?;
        let names: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
        check(
            s.material_index(b).is_some(),
            &format!("scene.body[{i}].material"),
            if b.material.is_empty() {
                format!("is required (materials: {})", names.join(", "))
            } else {
                format!(
                    "unknown material \"{}\" (defined: {})",
                    b.material,
                    names.join(", ")
                )
            },
        )?;
        check(
            b.velocity.iter().all(|v| v.is_finite()),
            &format!("scene.body[{i}].velocity"),
            "must be finite",
        )?;
        if let Some(flow) = &b.flow {
            let key = format!("scene.body[{i}].flow");
            flow.check(b.rect, s.periodic, s.gravity, &key)?;
            // Linear acoustics' closed box: the water fills it, walls at its sides.
            let fills = b.rect[..2].iter().all(|&v| v.abs() < 1e-9)
                && (0..2).all(|k| (b.rect[k + 2] - s.size[k]).abs() < 1e-9 * s.size[k]);
            check(
                fills || !matches!(flow, crate::flows::Flow::SoundWave { .. }),
                &format!("scene.body[{i}].rect"),
                "must fill the box, [0, 0, box width, box height], under a sound_wave flow",
            )?;
            check(
                flow.drift_scale(b.velocity) > 0.0,
                &format!("scene.body[{i}].velocity"),
                "must be nonzero under a grid_seed flow (its seed is a share of it)",
            )?;
        }
        Ok(())
    }

    /// Gates stand at the bodies' outer left and right edges: on cell lines,
    /// with the x axis walled.
    fn validate_gates(&self) -> Result<(), ConfigError> {
        let s = &self.scene;
        check(
            !s.periodic[0],
            "scene.initial",
            "\"hydrostatic_gate\" needs walls in x (scene.periodic[0] is true)",
        )?;
        let [x0, x1] = s.gated_span();
        for (edge, x) in [("left", x0), ("right", x1)] {
            let n = (x - s.origin[0]) / s.cell;
            check(
                (n - n.round()).abs() < 1e-6,
                "scene.initial",
                format!(
                    "\"hydrostatic_gate\" puts a gate at the bodies' {edge} edge, x = {x} m, \
                     which is not on a cell line (cell {} m from x = {} m)",
                    s.cell, s.origin[0]
                ),
            )?;
        }
        check(
            x1 - x0 >= 2.0 * s.cell - 1e-9,
            "scene.initial",
            format!(
                "\"hydrostatic_gate\": the bodies span {} m in x, less than two cells",
                x1 - x0
            ),
        )?;
        Ok(())
    }

    /// What the pressure-implicit step supports: one fluid, no tension
    /// cut, particle quadrature and the gradient force, no remedy (it has
    /// its own controls in `[method.projection]`).
    fn validate_pressure_implicit(&self) -> Result<(), ConfigError> {
        let (m, s) = (&self.method, &self.scene);
        validate_projection_ranges(&m.projection)?;
        let needs = |key: &str, what: &str| ConfigError {
            key: key.into(),
            message: format!("method.formulation = \"pressure_implicit\" {what}"),
        };
        if s.materials.len() != 1 {
            return Err(needs(
                "materials",
                &format!(
                    "solves one fluid phase (got {} materials)",
                    s.materials.len()
                ),
            ));
        }
        let mat = &s.materials[0];
        if mat.shear_modulus > 0.0 {
            return Err(needs(
                &mat.key(0, "shear_modulus"),
                "solves a fluid, not a solid",
            ));
        }
        if mat.pressure_floor.is_some() {
            return Err(needs(
                &mat.key(0, "pressure_floor"),
                "has no tension cut (the cut would make the solve a complementarity problem)",
            ));
        }
        if m.quadrature != QuadratureKind::Particles {
            return Err(needs(
                "method.quadrature",
                "integrates its pressure on the cells: use \"particles\"",
            ));
        }
        if m.force != ForceKind::Gradient {
            return Err(needs(
                "method.force",
                "takes the velocity gradient from the shape functions: use \"gradient\"",
            ));
        }
        if let Some(key) = m.remedies.active().first().map(|r| r.descriptor().key) {
            return Err(needs(
                &format!("method.{key}"),
                "takes no remedy (its own controls are [method.projection])",
            ));
        }
        self.validate_scheme()
    }

    /// The staggered scheme's own checks; the collocated one refuses the
    /// staggered scheme's keys.
    fn validate_scheme(&self) -> Result<(), ConfigError> {
        let p = &self.method.projection;
        check(
            p.surface_level == SurfaceLevel::Fraction || p.free_surface != FreeSurface::Cell,
            "method.projection.surface_level",
            "places a ghost surface: set method.projection.free_surface to \"ghost\" or \"ghost_orthogonal\", or use \"fraction\"",
        )?;
        check(
            is_default_surface_floor(&p.min_surface_share) || p.free_surface != FreeSurface::Cell,
            "method.projection.min_surface_share",
            "floors a ghost surface's theta: set method.projection.free_surface to \"ghost\" or \"ghost_orthogonal\", or leave it at 0.05",
        )?;
        check(
            p.share_floor == ShareFloor::Fixed || p.free_surface != FreeSurface::Cell,
            "method.projection.share_floor",
            "bounds a ghost surface's theta: set method.projection.free_surface to \"ghost\", or use \"fixed\"",
        )?;
        if p.scheme == ProjectionScheme::Mac {
            return self.validate_mac();
        }
        // Each staggered-only key, whether it is set, and its default.
        let staggered_only = [
            (
                "face_density",
                p.face_density != FaceDensity::Particles,
                "\"particles\"",
            ),
            ("holes", p.holes != Holes::Air, "\"air\""),
            ("advection", p.advection == Advection::Flux, "\"shape\""),
            (
                "advection_step",
                p.advection_step != AdvectionStep::Euler,
                "\"euler\"",
            ),
            ("theta", p.theta != 1.0, "1"),
            (
                "share_floor",
                p.share_floor != ShareFloor::Fixed,
                "\"fixed\"",
            ),
        ];
        match staggered_only.iter().find(|(_, set, _)| *set) {
            Some((key, _, default)) => Err(ConfigError {
                key: format!("method.projection.{key}"),
                message: format!("applies to the staggered scheme only: set method.projection.scheme = \"mac\", or use {default}"),
            }),
            None => Ok(()),
        }
    }

    /// What the staggered scheme supports: quadratic B-splines centred on
    /// the faces, PIC, FLIP or APIC, and a walled box.
    fn validate_mac(&self) -> Result<(), ConfigError> {
        let (m, s) = (&self.method, &self.scene);
        let needs = |key: &str, what: &str| ConfigError {
            key: key.into(),
            message: format!("method.projection.scheme = \"mac\" {what}"),
        };
        if m.shape != ShapeKind::Bspline2 {
            return Err(needs(
                "method.shape",
                "transfers with quadratic B-splines on the faces: use \"bspline2\"",
            ));
        }
        if m.transfer == TransferKind::Xpic {
            return Err(needs(
                "method.transfer",
                "takes \"pic\", \"flip\" or \"apic\" (XPIC smooths on the nodes)",
            ));
        }
        if s.periodic.iter().any(|&p| p) {
            return Err(needs(
                "scene.periodic",
                "needs walls on every side (both must be false)",
            ));
        }
        if m.projection.free_surface == FreeSurface::GhostOrthogonal {
            return Err(needs(
                "method.projection.free_surface",
                "takes \"cell\" or \"ghost\" (its divergence is each cell's flux balance, unweighted)",
            ));
        }
        if m.projection.drift_correction != DriftCorrection::Position {
            return Err(needs(
                "method.projection.drift_correction",
                "corrects the packing by position only: use \"position\"",
            ));
        }
        Ok(())
    }

    fn validate_materials(&self) -> Result<(), ConfigError> {
        let s = &self.scene;
        check(
            !s.materials.is_empty(),
            "materials",
            "at least one [materials.NAME] table is required",
        )?;
        for (i, m) in s.materials.iter().enumerate() {
            within(m.rho0, 1e-6, 1e6, &m.key(i, "rho0"))?;
            if m.k == f64::INFINITY {
                check(
                    self.method.formulation == Formulation::PressureImplicit,
                    &m.key(i, "K"),
                    "\"inf\" (incompressible) needs method.formulation = \"pressure_implicit\"",
                )?;
            } else {
                within(m.k, 1e-6, 1e13, &m.key(i, "K"))?;
            }
            within(m.gamma, 1.0, 20.0, &m.key(i, "gamma"))?;
            within(m.viscosity, 0.0, 1e6, &m.key(i, "viscosity"))?;
            within(m.j_res, 0.5, 2.0, &m.key(i, "j_res"))?;
            if let Some(p) = m.pressure_floor {
                within(p, -1e12, 1e12, &m.key(i, "pressure_floor"))?;
            }
            within(m.shear_modulus, 0.0, 1e13, &m.key(i, "shear_modulus"))?;
            within(m.softening_strain, 0.0, 1e6, &m.key(i, "softening_strain"))?;
            check(
                m.softening_strain == 0.0 || m.shear_modulus > 0.0,
                &m.key(i, "softening_strain"),
                "softens a solid's shear modulus: it needs shear_modulus > 0 (got 0, a fluid)",
            )?;
        }
        Ok(())
    }
}
