//! The named choices of a study (shape family, transfer, scheme, EOS,
//! walls, ...): plain enums that every module may use without depending on
//! the configuration that holds them.

use serde::{Deserialize, Serialize};

/// The keys of `[method]` that are not remedies (serde's own list is not
/// public; a test checks this one against `config::Method`'s serialisation).
pub const METHOD_KEYS: &[&str] = &[
    "shape",
    "transfer",
    "flip_alpha",
    "gradient_enhanced",
    "scheme",
    "cfl",
    "dt",
    "dt_value",
    "dt_min",
    "j_update",
    "force",
    "quadrature",
    "xpic_order",
    "formulation",
    "projection",
];

/// How the pressure is advanced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Formulation {
    /// Pressure from the EOS at every particle, explicit in time (the
    /// acoustic CFL limits the step).
    #[default]
    Explicit,
    /// One fluid's cell pressure solved implicitly each step (a projection
    /// at K = infinity); the step follows the flow, not the sound
    /// (`stages/projection.rs`, docs/physics.md section 8).
    PressureImplicit,
}

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
    /// CPDI (Sadeghirad et al. 2011): the particle's domain is the
    /// parallelogram F carries its undeformed square to (capped at one cell
    /// past the particle per axis), its weights the hats' mean over the
    /// four corners (`shapes/cpdi.rs`).
    Cpdi,
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
    /// Uintah's: dt = CFL min over the axes of h / max_p(c_p + |v_p,axis|),
    /// with c_p the tangent wave speed after the stress update and v_p the
    /// velocity the particle had at the start of the step, computed at the
    /// end of a step for the next; the first step takes c = sqrt(K / rho0)
    /// (the bulk modulus, not the tangent's gamma K).
    #[serde(rename = "per_axis")]
    PerAxis,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JUpdate {
    /// J = det((I + dt L) F).
    Det,
    /// J <- J exp(dt tr L): stays positive.
    Exp,
    /// Uintah's: F <- (I + dt L / n)^n F with n = min(max(1, 2 floor(|L| dt)),
    /// 10000) (|L| the Frobenius norm), J = det F: the plain update while
    /// |L| dt < 1, substeps beyond.
    Substeps,
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

/// What the walls do with the material images beyond them (wide shapes
/// put weight on the ghost nodes outside the box).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WallGhosts {
    /// Mirror walls: a ghost node's mass, momentum and force are folded
    /// (mirrored) onto its partner inside the box.
    #[default]
    Fold,
    /// Uintah's symmetry condition: what the particles put on a ghost node
    /// is discarded, and the ghost is overwritten with its partner's mirror
    /// image (MPMBoundCond.cc). Linear shapes never reach a ghost.
    Overwrite,
}

impl WallGhosts {
    pub fn is_fold(&self) -> bool {
        *self == WallGhosts::Fold
    }
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
    /// `on_inversion` only: the particle stays and its EOS is evaluated at
    /// its J <= 0 (Uintah's Water model before 2015-08-03, which had no J
    /// check); the monitor logs an `inversion` event and the run goes on.
    Keep,
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
