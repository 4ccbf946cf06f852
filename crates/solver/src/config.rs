//! Plain-data description of a scene and a method. The study crate fills these
//! from TOML; the solver only reads them.

use serde::{Deserialize, Serialize};

/// Shape-function family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShapeKind {
    /// Bilinear hat functions.
    Linear,
    /// Undeformed GIMP (particle half-width h / (2 ppc)).
    Gimp,
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

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InitialState {
    /// Zero stress, gravity jumps on at t = 0.
    ZeroStress,
    /// Discrete hydrostatic equilibrium (spaced by J, then damped relaxation).
    Hydrostatic,
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

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    pub rho0: f64,
    pub eos: EosKind,
    /// Low-pressure bulk modulus K (Pa).
    pub k: f64,
    pub gamma: f64,
    /// Dynamic viscosity (Pa s).
    pub viscosity: f64,
    /// Free thermal-expansion volume ratio: the EOS sees J / j_res.
    pub j_res: f64,
    /// Tension cutoff: pressure never goes below this (None = no cutoff).
    pub pressure_floor: Option<f64>,
}

impl Material {
    pub fn water(k: f64) -> Self {
        Material {
            rho0: 1000.0,
            eos: EosKind::Tait,
            k,
            gamma: 7.0,
            viscosity: 0.0,
            j_res: 1.0,
            pressure_floor: None,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Body {
    /// [x0, y0, x1, y1] in metres.
    pub rect: [f64; 4],
    /// Index into `Scene::materials`.
    pub material: usize,
    /// Initial velocity.
    pub velocity: [f64; 2],
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// Lower-left corner of the box (metres).
    pub origin: [f64; 2],
    /// Box width and height (metres); must be whole cells.
    pub size: [f64; 2],
    pub cell: f64,
    /// Particles per cell along each axis.
    pub ppc: usize,
    pub t_end: f64,
    /// Magnitude of gravity, acting in -y.
    pub gravity: f64,
    pub initial: InitialState,
    /// Periodic instead of symmetry-plane walls, per axis.
    pub periodic: [bool; 2],
    pub bodies: Vec<Body>,
    pub materials: Vec<Material>,
}

impl Scene {
    /// PHYSICS.md section 1: 0.8 x 0.6 box, 0.2 x 0.4 water column, h = 1 cm, 2 x 2 ppc.
    pub fn dam_break(material: Material) -> Self {
        Scene {
            origin: [0.0, 0.0],
            size: [0.8, 0.6],
            cell: 0.01,
            ppc: 2,
            t_end: 5.0,
            gravity: 9.81,
            initial: InitialState::ZeroStress,
            periodic: [false, false],
            bodies: vec![Body {
                rect: [0.0, 0.0, 0.2, 0.4],
                material: 0,
                velocity: [0.0, 0.0],
            }],
            materials: vec![material],
        }
    }

    /// Number of cells along each axis.
    pub fn cells(&self) -> [usize; 2] {
        [
            (self.size[0] / self.cell).round() as usize,
            (self.size[1] / self.cell).round() as usize,
        ]
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Method {
    pub shape: ShapeKind,
    pub transfer: TransferKind,
    pub flip_alpha: f64,
    pub scheme: SchemeKind,
    pub cfl: f64,
    pub dt: DtMode,
    /// Use this time step instead of the CFL one (benchmarks); None = CFL.
    pub dt_override: Option<f64>,
    pub j_update: JUpdate,
}

impl Method {
    /// The problem statement's baseline: linear, FLIP, USF, fixed dt, CFL 0.2.
    pub fn baseline() -> Self {
        Method {
            shape: ShapeKind::Linear,
            transfer: TransferKind::Flip,
            flip_alpha: 1.0,
            scheme: SchemeKind::Usf,
            cfl: 0.2,
            dt: DtMode::Fixed,
            dt_override: None,
            j_update: JUpdate::Det,
        }
    }
}

/// Fault injection: at step `step`, after G2P, add `dv` to every particle in `region`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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

impl SolverConfig {
    /// The dam break the benchmarks time (`kick bench`, criterion): power law
    /// gamma 7 at K = 150 kPa, the baseline method with `shape` and `transfer`.
    pub fn benchmark_dam_break(shape: ShapeKind, transfer: TransferKind, cell: f64) -> Self {
        let mut mat = Material::water(1.5e5);
        mat.eos = EosKind::Power;
        let mut scene = Scene::dam_break(mat);
        scene.cell = cell;
        let mut method = Method::baseline();
        method.shape = shape;
        method.transfer = transfer;
        SolverConfig {
            scene,
            method,
            perturb: vec![],
        }
    }

    /// Checks what the solver relies on; the study crate checks ranges earlier with file context.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let s = &self.scene;
        check(
            s.cell > 0.0 && s.cell.is_finite(),
            "scene.cell",
            "must be > 0",
        )?;
        for a in 0..2 {
            let n = s.size[a] / s.cell;
            check(
                s.size[a] > 0.0 && (n - n.round()).abs() < 1e-6 && n.round() >= 2.0,
                "scene.box",
                format!(
                    "box must be a whole number (>= 2) of cells of size {}",
                    s.cell
                ),
            )?;
        }
        check((1..=8).contains(&s.ppc), "scene.ppc", "allowed range 1..=8")?;
        check(s.t_end > 0.0, "scene.t_end", "must be > 0")?;
        check(s.gravity.is_finite(), "scene.gravity", "must be finite")?;
        check(
            !s.materials.is_empty(),
            "materials",
            "at least one material",
        )?;
        for (i, b) in s.bodies.iter().enumerate() {
            let key = format!("scene.body[{i}].rect");
            check(
                b.rect[0] < b.rect[2] && b.rect[1] < b.rect[3],
                &key,
                "needs x0 < x1 and y0 < y1",
            )?;
            check(
                b.rect[0] >= s.origin[0] - 1e-12
                    && b.rect[1] >= s.origin[1] - 1e-12
                    && b.rect[2] <= s.origin[0] + s.size[0] + 1e-12
                    && b.rect[3] <= s.origin[1] + s.size[1] + 1e-12,
                &key,
                "must lie inside the box",
            )?;
            check(
                b.material < s.materials.len(),
                &format!("scene.body[{i}].material"),
                "unknown material",
            )?;
        }
        for (i, m) in s.materials.iter().enumerate() {
            let key = |k: &str| format!("materials[{i}].{k}");
            check(m.rho0 > 0.0, &key("rho0"), "must be > 0")?;
            check(m.k > 0.0, &key("K"), "must be > 0")?;
            check(m.gamma > 0.0, &key("gamma"), "must be > 0")?;
            check(m.viscosity >= 0.0, &key("viscosity"), "must be >= 0")?;
            check(m.j_res > 0.0, &key("j_res"), "must be > 0")?;
        }
        let m = &self.method;
        check(
            (0.0..=1.0).contains(&m.flip_alpha),
            "method.flip_alpha",
            "allowed range 0..=1",
        )?;
        check(
            m.cfl > 0.0 && m.cfl <= 1.0,
            "method.cfl",
            "allowed range (0, 1]",
        )?;
        if let Some(dt) = m.dt_override {
            check(dt > 0.0, "method.dt_override", "must be > 0")?;
        }
        Ok(())
    }
}
