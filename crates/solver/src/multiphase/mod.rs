//! Two phases as interacting bodies (docs/physics.md section 6): the
//! mixture steps a solid and a fluid solver over one grid and couples them
//! through drag, the pore pressure, a top load and an inflow wall.

pub mod boundary_inflow;
pub mod coupling;
pub mod drag;
mod drag_particle;
pub mod mixture;
pub mod pore_pressure;
