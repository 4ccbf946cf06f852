//! Particle seeding: n x n particles per cell at ((k + 1/2) / n) h, and the
//! hydrostatic lattice (rows spaced by their J under the strip's weight).

use crate::config::{InitialState, Scene};
use crate::particles::{Mat2, Particles, Vec2};

pub fn seed(scene: &Scene) -> Particles {
    let mut ps = Particles::default();
    let h = scene.cell;
    let l = h / scene.ppc as f64;
    for body in &scene.bodies {
        let material = scene.material_index(body).expect("validated");
        let mat = &scene.materials[material];
        // The lattice volume l^2 and its mass, times the body's volume
        // fraction (in the order the single-phase figures were computed in).
        let (share, mass) = (l * l * body.fraction, mat.rho0 * l * l * body.fraction);
        let [x0, y0, x1, y1] = body.rect;
        // Lattice positions origin + (k + 1/2) l that fall inside the rectangle.
        let first = |lo: f64, o: f64| ((lo - o) / l - 0.5).ceil().max(0.0) as i64;
        let last = |hi: f64, o: f64| ((hi - o) / l - 0.5).ceil() as i64;
        let (ix0, ix1) = (first(x0, scene.origin[0]), last(x1, scene.origin[0]));
        let (iy0, iy1) = (first(y0, scene.origin[1]), last(y1, scene.origin[1]));
        let rows = (iy1 - iy0).max(0) as usize;
        for ix in ix0..ix1 {
            let x = scene.origin[0] + (ix as f64 + 0.5) * l;
            match scene.initial {
                InitialState::ZeroStress => {
                    for iy in iy0..iy1 {
                        let y = scene.origin[1] + (iy as f64 + 0.5) * l;
                        ps.push(
                            Vec2::new(x, y),
                            Vec2::from(body.velocity),
                            mass,
                            share,
                            material as u16,
                        );
                    }
                }
                InitialState::Hydrostatic | InitialState::HydrostaticGate => {
                    // Row k from the top carries p = rho0 g l (k + 1/2): exactly the
                    // clamped mass-above reference of docs/physics.md on this lattice.
                    let mut y = scene.origin[1] + iy0 as f64 * l;
                    let mut prev_half = 0.0;
                    for row in 0..rows {
                        let k_top = (rows - 1 - row) as f64;
                        let p = mat.rho0 * scene.gravity * l * (k_top + 0.5);
                        let j = mat.j_at_pressure(p);
                        y += prev_half + 0.5 * j * l;
                        prev_half = 0.5 * j * l;
                        ps.push(
                            Vec2::new(x, y),
                            Vec2::from(body.velocity),
                            mass,
                            share,
                            material as u16,
                        );
                        let q = ps.len() - 1;
                        ps.f[q] = Mat2::new(1.0, 0.0, 0.0, j);
                        ps.j[q] = j;
                        ps.vol[q] = j * l * l * body.fraction;
                        ps.pressure[q] = p;
                        ps.stress[q] = -p * Mat2::identity();
                    }
                }
            }
        }
    }
    jitter(&mut ps, scene);
    ps
}

/// Ensemble members: each position moved by a seeded uniform offset of at
/// most `scene.jitter` h per axis (nothing when the jitter is 0).
fn jitter(ps: &mut Particles, scene: &Scene) {
    jitter_positions(&mut ps.x, scene.jitter * scene.cell, scene.seed);
}

/// Moves each position by a uniform offset of at most `amplitude` per axis,
/// from the seed's own stream (nothing when the amplitude is 0).
pub fn jitter_positions(x: &mut [Vec2], amplitude: f64, seed: u64) {
    if amplitude == 0.0 {
        return;
    }
    let mut state = seed ^ 0x6a09_e667_f3bc_c909;
    let mut uniform = || uniform01(&mut state);
    for x in x.iter_mut() {
        x.x += amplitude * (2.0 * uniform() - 1.0);
        x.y += amplitude * (2.0 * uniform() - 1.0);
    }
}

/// The next number of a splitmix64 stream, uniform in [0, 1): a fixed,
/// platform-independent sequence per starting state.
pub fn uniform01(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}
