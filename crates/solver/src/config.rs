//! Plain-data description of a scene and a method. The study crate fills these
//! from TOML; the solver only reads them.

use crate::remedies::RemedySettings;
use serde::{Deserialize, Serialize};

/// The keys of `[method]` that are not remedies (serde's own list is not
/// public; a test checks this one against `Method`'s serialisation).
pub const METHOD_KEYS: &[&str] = &[
    "shape",
    "transfer",
    "flip_alpha",
    "scheme",
    "cfl",
    "dt",
    "dt_value",
    "j_update",
    "force",
    "quadrature",
    "xpic_order",
];

/// Shape-function family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShapeKind {
    /// Bilinear hat functions.
    Linear,
    /// Undeformed GIMP (particle half-width h / (2 ppc)).
    Gimp,
    /// Convected-particle GIMP: the half-widths follow F's diagonal
    /// (a suspect for "once highly deformed" mattering, not a remedy).
    Cpgimp,
    /// Quadratic B-spline.
    Bspline2,
    /// Cubic B-spline.
    Bspline3,
}

/// Particle/grid velocity transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TransferKind {
    Pic,
    /// FLIP blended with PIC by `Method::flip_alpha` (1 = pure FLIP).
    Flip,
    Apic,
    /// XPIC(m) (Hammerquist & Nairn 2017), m = `Method::xpic_order`.
    Xpic,
}

/// When the stress is updated relative to the grid momentum update.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SchemeKind {
    /// Update stress first (from the P2G velocity).
    Usf,
    /// Update stress last (from the updated grid velocity).
    Usl,
    /// Modified USL: stress from the velocity re-projected from the particles.
    Musl,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DtMode {
    /// CFL step taken once at t = 0 (the problem statement's setting).
    Fixed,
    /// CFL step recomputed every step.
    Dynamic,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JUpdate {
    /// J = det((I + dt L) F).
    Det,
    /// J <- J exp(dt tr L): stays positive.
    Exp,
}

/// How `method.j_bar` reconstructs J on the grid before interpolating it
/// back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JBarFit {
    /// Each node takes the mass-weighted mean of J (Zhao, Jiang & Choo
    /// 2023): a linear J field is bent at the edges of the material.
    #[default]
    Constant,
    /// Each node fits J by mass-weighted least squares to a plane over its
    /// support and the particle reads the planes back: any linear J field
    /// (the hydrostatic one) is kept wherever the support spans both axes.
    Linear,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InitialState {
    /// Zero stress, gravity jumps on at t = 0.
    ZeroStress,
    /// Discrete hydrostatic equilibrium (spaced by J, then damped relaxation).
    Hydrostatic,
    /// The same equilibrium reached behind gates at the bodies' left and right
    /// edges, lifted at t = 0: a dam-break column standing at rest before its
    /// release, as in the experiments (zero stress would add a fall under
    /// gravity that the experiment does not have).
    HydrostaticGate,
}

/// How the internal force and the velocity gradient are discretised.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ForceKind {
    /// f_i = -sum V sigma grad N_i, L = sum v_i grad N_i^T.
    #[default]
    Gradient,
    /// MLS-MPM (Hu et al. 2018): f_i = -sum V sigma D^-1 (x_i - x_p) N_i and
    /// L = C (the APIC affine matrix); B-splines and APIC only.
    Mls,
}

/// Where the internal force is integrated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum QuadratureKind {
    /// At the material points (MPM's own quadrature).
    #[default]
    Particles,
    /// At fixed points in the cells full of material, at the material
    /// points elsewhere (mixed integration, Beuth 2012; `quadrature_mixed`).
    Mixed,
}

/// A wall of the box.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Wall {
    Left,
    Right,
    Floor,
    Top,
}

/// What happens to a particle that leaves the box or inverts (J <= 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OnLoss {
    /// The monitor stops the run (status `blew_up`).
    #[default]
    Stop,
    /// The solver deletes it at the end of the step and counts it (Uintah's
    /// behaviour); the run stops once `lost_mass_limit` of the mass is gone.
    Delete,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EosKind {
    /// p = K (J^-gamma - 1).
    Power,
    /// p = C K [exp((1 - J)/C) - 1], C = 0.0894.
    Tait,
    /// p = K (1 - J) (the mpm88 benchmark's fluid).
    Linear,
}

/// A fluid material: a `[materials.NAME]` table of a study file. Every key
/// but `K` is optional; the defaults below are the only ones.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// The study file's table name (`water` in `[materials.water]`).
    #[serde(skip)]
    pub name: String,
    /// Reference density (kg/m^3).
    #[serde(default = "defaults::rho0")]
    pub rho0: f64,
    #[serde(default = "defaults::eos")]
    pub eos: EosKind,
    /// Low-pressure bulk modulus K (Pa).
    #[serde(rename = "K")]
    pub k: f64,
    /// Power-law exponent (power EOS only).
    #[serde(default = "defaults::gamma")]
    pub gamma: f64,
    /// Dynamic viscosity (Pa s).
    #[serde(default)]
    pub viscosity: f64,
    /// Free thermal-expansion volume ratio: the EOS sees J / j_res.
    #[serde(default = "defaults::j_res")]
    pub j_res: f64,
    /// Tension cutoff (Pa): pressure never goes below this (absent = no cutoff).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure_floor: Option<f64>,
    /// Shear modulus G (Pa) of the neo-Hookean shear part: 0 = a fluid.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub shear_modulus: f64,
    /// Shear softening (the unified model's history variable xi, the
    /// accumulated equivalent shear strain): G(xi) = G exp(-xi /
    /// softening_strain), so a solid sheared far enough becomes the fluid
    /// U(J) + 2 mu dev D. 0 = none (G stays G).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub softening_strain: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// Defaults of the optional material keys (one definition, used by serde and `Material::new`).
mod defaults {
    use super::EosKind;
    pub fn rho0() -> f64 {
        1000.0
    }
    pub fn eos() -> EosKind {
        EosKind::Power
    }
    pub fn gamma() -> f64 {
        7.0
    }
    pub fn j_res() -> f64 {
        1.0
    }
}

impl Material {
    /// Water with every default (power law, gamma 7) and bulk modulus `k`.
    pub fn new(k: f64) -> Self {
        Material {
            name: String::new(),
            rho0: defaults::rho0(),
            eos: defaults::eos(),
            k,
            gamma: defaults::gamma(),
            viscosity: 0.0,
            j_res: defaults::j_res(),
            pressure_floor: None,
            shear_modulus: 0.0,
            softening_strain: 0.0,
        }
    }

    /// Water with the Tait EOS and bulk modulus `k`, otherwise the defaults.
    pub fn tait(k: f64) -> Self {
        Material {
            eos: EosKind::Tait,
            ..Material::new(k)
        }
    }

    /// The study key of field `field` of this material.
    fn key(&self, index: usize, field: &str) -> String {
        if self.name.is_empty() {
            format!("materials[{index}].{field}")
        } else {
            format!("materials.{}.{field}", self.name)
        }
    }
}

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
    /// Fraction of the initial mass that deleted particles may take before
    /// the run counts as blown up (the harness's convention, not Uintah's).
    pub lost_mass_limit: f64,
    /// Walls with zero tangential grid velocity (the others are free-slip
    /// symmetry planes), e.g. `no_slip = ["floor"]`.
    pub no_slip: Vec<Wall>,
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
            lost_mass_limit: 0.1,
            no_slip: vec![],
            bodies: vec![],
            materials: vec![],
        }
    }
}

impl Wall {
    /// The axis the wall is normal to.
    pub fn axis(self) -> usize {
        match self {
            Wall::Left | Wall::Right => 0,
            Wall::Floor | Wall::Top => 1,
        }
    }

    /// Flags per [axis][low side, high side] of the given walls.
    pub fn mask(walls: &[Wall]) -> [[bool; 2]; 2] {
        let mut mask = [[false; 2]; 2];
        for w in walls {
            let side = usize::from(matches!(w, Wall::Right | Wall::Top));
            mask[w.axis()][side] = true;
        }
        mask
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
    pub scheme: SchemeKind,
    /// Courant number of the time step.
    pub cfl: f64,
    pub dt: DtMode,
    /// Use this time step (s) instead of the CFL one (benchmarks); absent = CFL.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_value: Option<f64>,
    pub j_update: JUpdate,
    /// Force and velocity-gradient discretisation (`gradient` or `mls`).
    pub force: ForceKind,
    /// Where the internal force is integrated: `particles` or `mixed`
    /// (fixed points in the cells full of material).
    pub quadrature: QuadratureKind,
    /// The order m of `transfer = "xpic"` (1 = PIC).
    pub xpic_order: u32,
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
            scheme: SchemeKind::Usf,
            cfl: 0.2,
            dt: DtMode::Fixed,
            dt_value: None,
            j_update: JUpdate::Det,
            force: ForceKind::Gradient,
            quadrature: QuadratureKind::Particles,
            xpic_order: 2,
            remedies: RemedySettings::default(),
        }
    }
}

impl Method {
    /// The problem statement's baseline (the defaults).
    pub fn baseline() -> Self {
        Method::default()
    }
}

/// Fault injection (`[[perturb]]`): at step `step`, after G2P, add `dv` to every particle in
/// `region`, an impulse: dv / dt is also added to its force-driven acceleration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Perturb {
    pub step: u64,
    /// [x0, y0, x1, y1] in metres.
    pub region: [f64; 4],
    pub dv: [f64; 2],
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverConfig {
    pub scene: Scene,
    pub method: Method,
    pub perturb: Vec<Perturb>,
}

/// A configuration the solver cannot run, with the offending key.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigError {
    pub key: String,
    pub message: String,
}

impl std::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.key, self.message)
    }
}

impl std::error::Error for ConfigError {}

fn check(ok: bool, key: &str, message: impl Into<String>) -> Result<(), ConfigError> {
    if ok {
        Ok(())
    } else {
        Err(ConfigError {
            key: key.to_string(),
            message: message.into(),
        })
    }
}

/// `lo <= v <= hi` (and finite), else "`v` is out of range (allowed lo ..= hi)".
fn within(v: f64, lo: f64, hi: f64, key: &str) -> Result<(), ConfigError> {
    check(
        v.is_finite() && (lo..=hi).contains(&v),
        key,
        format!("{v} is out of range (allowed {lo} ..= {hi})"),
    )
}

fn ordered_rect(r: &[f64; 4], key: &str) -> Result<(), ConfigError> {
    check(
        r.iter().all(|v| v.is_finite()) && r[0] < r[2] && r[1] < r[3],
        key,
        "needs x0 < x1 and y0 < y1",
    )
}

impl SolverConfig {
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
        within(m.cfl, 1e-4, 1.0, "method.cfl")?;
        if let Some(dt) = m.dt_value {
            within(dt, 1e-12, 1.0, "method.dt_value")?;
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
        m.remedies.validate(self)?;
        for (i, p) in self.perturb.iter().enumerate() {
            check(p.step >= 1, &format!("perturb[{i}].step"), "must be >= 1")?;
            ordered_rect(&p.region, &format!("perturb[{i}].region"))?;
            check(
                p.dv.iter().all(|v| v.is_finite()),
                &format!("perturb[{i}].dv"),
                "must be finite",
            )?;
        }
        Ok(())
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
        }
        if s.initial == InitialState::HydrostaticGate {
            self.validate_gates()?;
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

    fn validate_materials(&self) -> Result<(), ConfigError> {
        let s = &self.scene;
        check(
            !s.materials.is_empty(),
            "materials",
            "at least one [materials.NAME] table is required",
        )?;
        for (i, m) in s.materials.iter().enumerate() {
            within(m.rho0, 1e-6, 1e6, &m.key(i, "rho0"))?;
            within(m.k, 1e-6, 1e13, &m.key(i, "K"))?;
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
