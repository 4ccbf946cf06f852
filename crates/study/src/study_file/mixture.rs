//! A two-phase study's `[drag]` table and its checks of the phases'
//! bodies.

use super::*;

/// The `[drag]` table: the scene is a two-phase mixture (docs/physics.md
/// section 6) whose bodies each name their `phase`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DragTable {
    /// B (kg m^-3 s^-1), the drag per mixture volume per unit relative velocity.
    coefficient: Option<f64>,
    /// Or the skeleton's permeability k (m^2): B = n^2 mu / k with the fluid
    /// material's viscosity mu and the fluid bodies' fraction n.
    permeability: Option<f64>,
    /// Kozeny-Carman scaling of B with the nodal porosity, from this reference porosity.
    kozeny_carman: Option<f64>,
    #[serde(default)]
    model: DragModel,
    #[serde(default)]
    update: DragUpdate,
    /// The solid is a fixed skeleton (its grid velocity held at zero).
    #[serde(default)]
    fixed_solid: bool,
    /// The fluid's pressure on the grid from each node's volume balance
    /// (grains incompressible; the fluid's material is the pore fluid).
    #[serde(default)]
    pore_pressure: bool,
    /// The pore pressure averaged over each node's neighbours ([1 2 1] / 4
    /// per axis), which removes its node-to-node mode (needs pore_pressure).
    #[serde(default)]
    pore_node_average: bool,
    /// The volume constraint n_s + n_f <= 1 per node (the fluid keeps its
    /// own pressure; not with pore_pressure, which balances volumes already).
    #[serde(default)]
    volume_constraint: bool,
    /// A downward traction (Pa) on the solid's top surface.
    #[serde(default)]
    top_traction: f64,
    /// Seconds over which that traction ramps up from 0.
    #[serde(default)]
    traction_ramp: f64,
    /// Drained walls (e.g. the top): the pore pressure is `drained_pressure`
    /// there and the wall is open (what crosses it flows out).
    #[serde(default)]
    drained: Vec<Wall>,
    /// The pore pressure (Pa) on the drained walls.
    #[serde(default)]
    drained_pressure: f64,
    /// Inflow walls (e.g. the floor): the water enters through them at
    /// `inflow_velocity`; open to the water, a wall to the grains.
    #[serde(default)]
    inflow: Vec<Wall>,
    /// The water's speed into the box (m/s) through the inflow walls.
    #[serde(default)]
    inflow_velocity: f64,
}

/// A mixture case's interaction: the resolved `[drag]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct MixtureSpec {
    pub drag: Drag,
    pub fixed_solid: bool,
    pub pore_pressure: bool,
    pub pore_node_average: bool,
    pub volume_constraint: bool,
    pub top_traction: f64,
    pub traction_ramp: f64,
    pub drained: Vec<Wall>,
    pub drained_pressure: f64,
    pub inflow: Vec<Wall>,
    pub inflow_velocity: f64,
}

/// Checks a mixture's bodies and resolves its `[drag]` table.
pub(super) fn mixture_spec(t: &DragTable, solver: &SolverConfig) -> Result<MixtureSpec, KeyError> {
    mixture_bodies(solver)?;
    let coefficient = drag_coefficient(t, solver)?;
    check_drag_options(t, solver)?;
    Ok(MixtureSpec {
        drag: Drag {
            coefficient,
            kozeny_carman: t.kozeny_carman,
            model: t.model,
            update: t.update,
        },
        fixed_solid: t.fixed_solid,
        pore_pressure: t.pore_pressure,
        pore_node_average: t.pore_node_average,
        volume_constraint: t.volume_constraint,
        top_traction: t.top_traction,
        traction_ramp: t.traction_ramp,
        drained: t.drained.clone(),
        drained_pressure: t.drained_pressure,
        inflow: t.inflow.clone(),
        inflow_velocity: t.inflow_velocity,
    })
}

/// A body of each phase, every body with one, no perturbation, and no
/// overlap but of the two phases with n_s + n_f <= 1.
fn mixture_bodies(solver: &SolverConfig) -> Result<(), KeyError> {
    let bodies = &solver.scene.bodies;
    if let Some(i) = bodies.iter().position(|b| b.phase.is_none()) {
        return Err((
            format!("scene.body[{i}].phase"),
            "is required in a mixture (allowed: solid | fluid)".into(),
        ));
    }
    for phase in Phase::ALL {
        if !bodies.iter().any(|b| b.phase == Some(phase)) {
            return Err((
                "scene.body".into(),
                format!(
                    "a mixture needs a body of each phase: none is {}",
                    phase.name()
                ),
            ));
        }
    }
    if !solver.perturb.is_empty() {
        return Err((
            "perturb".into(),
            "is not available in a mixture yet (allowed: single-phase scenes)".into(),
        ));
    }
    overlaps(bodies)
}

/// Overlapping bodies of the two phases share the volume: n_s + n_f <= 1;
/// two bodies of one phase may not overlap.
fn overlaps(bodies: &[solver::Body]) -> Result<(), KeyError> {
    for (i, a) in bodies.iter().enumerate() {
        for (j, b) in bodies.iter().enumerate().skip(i + 1) {
            let overlap = a.rect[0] < b.rect[2]
                && b.rect[0] < a.rect[2]
                && a.rect[1] < b.rect[3]
                && b.rect[1] < a.rect[3];
            if overlap && a.phase != b.phase {
                if a.fraction + b.fraction > 1.0 + 1e-12 {
                    return Err((
                        format!("scene.body[{j}].fraction"),
                        format!(
                            "{} with body {i}'s {} over the same ground exceeds 1 (allowed: n_s + n_f <= 1)",
                            b.fraction, a.fraction
                        ),
                    ));
                }
            } else if overlap {
                return Err((
                    format!("scene.body[{j}].rect"),
                    format!("overlaps body {i} of the same phase (allowed: one body per phase and place)"),
                ));
            }
        }
    }
    Ok(())
}

/// The drag coefficient B (kg m^-3 s^-1): `drag.coefficient`, or from
/// `drag.permeability` and the fluid's viscosity and fraction.
fn drag_coefficient(t: &DragTable, solver: &SolverConfig) -> Result<f64, KeyError> {
    let bodies = &solver.scene.bodies;
    let positive = |key: &str, v: f64| {
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err((
                key.to_string(),
                format!("{v} is out of range (allowed: finite > 0)"),
            ))
        }
    };
    match (t.coefficient, t.permeability) {
        (Some(b), None) => {
            if b >= 0.0 && b.is_finite() {
                Ok(b)
            } else {
                Err((
                    "drag.coefficient".into(),
                    format!("{b} is out of range (allowed: finite >= 0 kg m^-3 s^-1)"),
                ))
            }
        }
        (None, Some(k)) => {
            let k = positive("drag.permeability", k)?;
            let fluid = bodies
                .iter()
                .find(|b| b.phase == Some(Phase::Fluid))
                .expect("checked above");
            let material = solver.scene.material_index(fluid).expect("validated");
            let mu = solver.scene.materials[material].viscosity;
            if mu <= 0.0 {
                return Err((
                    format!("materials.{}.viscosity", solver.scene.materials[material].name),
                    format!("{mu}: drag.permeability needs the fluid's viscosity > 0 (or give drag.coefficient)"),
                ));
            }
            Ok(Drag::from_permeability(mu, k, fluid.fraction))
        }
        _ => Err((
            "drag".into(),
            "give exactly one of `coefficient` (kg m^-3 s^-1) and `permeability` (m^2)".into(),
        )),
    }
}

/// The drag table's options agree with one another and with the scene's
/// walls: the update, volume constraint, pore pressure, drained and inflow
/// walls, Kozeny-Carman porosity and the top traction.
fn check_drag_options(t: &DragTable, solver: &SolverConfig) -> Result<(), KeyError> {
    if t.model.is_particle_based() && t.update != DragUpdate::Explicit {
        return Err((
            "drag.update".into(),
            "the particle-based model is explicit (allowed: explicit)".into(),
        ));
    }
    if t.volume_constraint && t.pore_pressure {
        return Err((
            "drag.volume_constraint".into(),
            "not with pore_pressure = true, whose volume balance holds the constraint already (allowed: one of them)".into(),
        ));
    }
    if t.pore_node_average && !t.pore_pressure {
        return Err((
            "drag.pore_node_average".into(),
            "it needs drag.pore_pressure = true (allowed: false without it)".into(),
        ));
    }
    solver::multiphase::mixture::check_drained(
        &solver.scene,
        &t.drained,
        t.drained_pressure,
        t.pore_pressure,
    )
    .map_err(|e| (e.key, e.message))?;
    solver::multiphase::mixture::check_inflow(
        &solver.scene,
        &t.inflow,
        t.inflow_velocity,
        t.pore_pressure,
        Wall::mask(&t.drained),
    )
    .map_err(|e| (e.key, e.message))?;
    if let Some(n0) = t.kozeny_carman {
        if !(n0 > 0.0 && n0 < 1.0) {
            return Err((
                "drag.kozeny_carman".into(),
                format!("{n0} is out of range (allowed: a reference porosity in (0, 1))"),
            ));
        }
    }
    for (key, v) in [
        ("drag.top_traction", t.top_traction),
        ("drag.traction_ramp", t.traction_ramp),
    ] {
        if !(v >= 0.0 && v.is_finite()) {
            return Err((
                key.into(),
                format!("{v} is out of range (allowed: finite >= 0)"),
            ));
        }
    }
    Ok(())
}
