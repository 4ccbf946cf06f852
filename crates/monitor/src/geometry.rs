//! Box, cells and scales the monitor's metrics are defined on.

use solver::{Material, Scene, Vec2};

#[derive(Clone, Debug, PartialEq)]
pub struct Geometry {
    pub origin: Vec2,
    pub size: Vec2,
    pub cell: f64,
    pub cells: [usize; 2],
    pub ppc: usize,
    pub gravity: f64,
    pub rho0: f64,
    /// The first material, whose EOS the rest layer of the hydrostatic floor obeys.
    pub material: Option<Material>,
    /// Initial column height H (tallest body) and width a (widest body).
    pub column_height: f64,
    pub column_width: f64,
    /// The bodies' largest uniform speed |velocity| at t = 0 (m/s): a body
    /// thrown at U (the ringing test's drift) is not escaping at U.
    pub body_speed: f64,
    /// Which axes wrap (else walls bound them).
    pub periodic: [bool; 2],
}

impl Geometry {
    pub fn from_scene(scene: &Scene) -> Self {
        let height = scene
            .bodies
            .iter()
            .map(|b| b.rect[3] - b.rect[1])
            .fold(0.0, f64::max);
        let width = scene
            .bodies
            .iter()
            .map(|b| b.rect[2] - b.rect[0])
            .fold(0.0, f64::max);
        Geometry {
            origin: Vec2::from(scene.origin),
            size: Vec2::from(scene.size),
            cell: scene.cell,
            cells: scene.cells(),
            ppc: scene.ppc,
            gravity: scene.gravity,
            rho0: scene.materials.first().map_or(1000.0, |m| m.rho0),
            material: scene.materials.first().cloned(),
            column_height: height,
            column_width: width,
            body_speed: scene
                .bodies
                .iter()
                .map(|b| b.velocity[0].hypot(b.velocity[1]))
                .fold(0.0, f64::max),
            periodic: scene.periodic,
        }
    }

    pub fn cell_count(&self) -> usize {
        self.cells[0] * self.cells[1]
    }

    /// Cell (i, j) holding `x`, clamped to the box.
    #[inline]
    pub fn cell_of(&self, x: Vec2) -> (usize, usize) {
        let r = (x - self.origin) / self.cell;
        let clamp = |v: f64, n: usize| {
            if v.is_finite() {
                // Truncation is floor here: the value is clamped to >= 0 first.
                (v.max(0.0) as usize).min(n - 1)
            } else {
                0
            }
        };
        (clamp(r.x, self.cells[0]), clamp(r.y, self.cells[1]))
    }

    #[inline]
    pub fn cell_index(&self, x: Vec2) -> usize {
        let (i, j) = self.cell_of(x);
        i + j * self.cells[0]
    }

    /// A cell is filled when it holds at least half of ppc^2 particles.
    pub fn filled_min(&self) -> u32 {
        (self.ppc * self.ppc).div_ceil(2) as u32
    }
}
