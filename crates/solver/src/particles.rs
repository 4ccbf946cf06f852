//! Structure-of-arrays particle storage. Arrays stay in id order; the sort stage
//! keeps a separate cell ordering so that ids and array slots never diverge.

use nalgebra::{Matrix2, Vector2};

pub type Vec2 = Vector2<f64>;
pub type Mat2 = Matrix2<f64>;

#[derive(Clone, Debug, Default)]
pub struct Particles {
    pub x: Vec<Vec2>,
    pub v: Vec<Vec2>,
    /// Velocity at the start of the last step.
    pub v_prev: Vec<Vec2>,
    /// Force-driven acceleration of the last step, sum_i N_i (v_i^new - v_i) / dt
    /// (FLIP's exact increment, walls applied), plus any `[[perturb]]` impulse
    /// over dt. The rest of v - v_prev is the transfer's own jump.
    pub accel: Vec<Vec2>,
    /// APIC affine velocity (zero for PIC/FLIP).
    pub affine: Vec<Mat2>,
    /// Full deformation gradient (in-plane; F_zz = 1).
    pub f: Vec<Mat2>,
    pub j: Vec<f64>,
    pub mass: Vec<f64>,
    pub vol0: Vec<f64>,
    pub vol: Vec<f64>,
    /// In-plane Cauchy stress.
    pub stress: Vec<Mat2>,
    pub pressure: Vec<f64>,
    /// |dev D| (3D deviator, plane strain), 1/s.
    pub dev_rate: Vec<f64>,
    /// The unified model's history variable xi: the accumulated equivalent
    /// shear strain, integral of sqrt(2 dev D : dev D) dt (3D deviator). It
    /// grows only in a softening solid (`softening_strain > 0`); 0 elsewhere.
    pub history: Vec<f64>,
    /// EOS figures of the current J, cached by the stress stage so the time
    /// step and the energy need no second EOS evaluation: c(J) and V0 U(J).
    pub wave_speed: Vec<f64>,
    pub stored_energy: Vec<f64>,
    pub material: Vec<u16>,
    pub id: Vec<u32>,
}

impl Particles {
    /// Scales particle `p`'s J by `factor` (F isotropically, V = J V0):
    /// a planted stress outlier, whose stress follows at the next stress update.
    pub fn scale_j(&mut self, p: usize, factor: f64) {
        self.j[p] *= factor;
        self.f[p] *= factor.sqrt();
        self.vol[p] = self.vol0[p] * self.j[p];
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    #[allow(clippy::too_many_arguments)]
    pub fn push(&mut self, x: Vec2, v: Vec2, mass: f64, vol0: f64, material: u16) {
        let id = self.x.len() as u32;
        self.x.push(x);
        self.v.push(v);
        self.v_prev.push(v);
        self.accel.push(Vec2::zeros());
        self.affine.push(Mat2::zeros());
        self.f.push(Mat2::identity());
        self.j.push(1.0);
        self.mass.push(mass);
        self.vol0.push(vol0);
        self.vol.push(vol0);
        self.stress.push(Mat2::zeros());
        self.pressure.push(0.0);
        self.dev_rate.push(0.0);
        self.history.push(0.0);
        self.wave_speed.push(0.0);
        self.stored_energy.push(0.0);
        self.material.push(material);
        self.id.push(id);
    }
}

impl Particles {
    /// Keeps the particles for which `keep(p)` holds, in id order, without
    /// reallocating; `keep` sees each slot's state before any is moved.
    pub fn retain(&mut self, mut keep: impl FnMut(&Particles, usize) -> bool) -> usize {
        let n = self.len();
        let mut w = 0;
        for p in 0..n {
            if !keep(self, p) {
                continue;
            }
            if w != p {
                self.move_slot(p, w);
            }
            w += 1;
        }
        self.truncate(w);
        n - w
    }

    fn move_slot(&mut self, from: usize, to: usize) {
        self.x[to] = self.x[from];
        self.v[to] = self.v[from];
        self.v_prev[to] = self.v_prev[from];
        self.accel[to] = self.accel[from];
        self.affine[to] = self.affine[from];
        self.f[to] = self.f[from];
        self.j[to] = self.j[from];
        self.mass[to] = self.mass[from];
        self.vol0[to] = self.vol0[from];
        self.vol[to] = self.vol[from];
        self.stress[to] = self.stress[from];
        self.pressure[to] = self.pressure[from];
        self.dev_rate[to] = self.dev_rate[from];
        self.history[to] = self.history[from];
        self.wave_speed[to] = self.wave_speed[from];
        self.stored_energy[to] = self.stored_energy[from];
        self.material[to] = self.material[from];
        self.id[to] = self.id[from];
    }

    /// Sets the particle count to `n` (new slots zeroed, to be overwritten:
    /// restoring a checkpoint).
    pub fn resize(&mut self, n: usize) {
        if n <= self.len() {
            return self.truncate(n);
        }
        self.x.resize(n, Vec2::zeros());
        self.v.resize(n, Vec2::zeros());
        self.v_prev.resize(n, Vec2::zeros());
        self.accel.resize(n, Vec2::zeros());
        self.affine.resize(n, Mat2::zeros());
        self.f.resize(n, Mat2::identity());
        self.j.resize(n, 1.0);
        self.mass.resize(n, 0.0);
        self.vol0.resize(n, 0.0);
        self.vol.resize(n, 0.0);
        self.stress.resize(n, Mat2::zeros());
        self.pressure.resize(n, 0.0);
        self.dev_rate.resize(n, 0.0);
        self.history.resize(n, 0.0);
        self.wave_speed.resize(n, 0.0);
        self.stored_energy.resize(n, 0.0);
        self.material.resize(n, 0);
        self.id.resize(n, 0);
    }

    /// Room for `extra` more particles in every array (no reallocation
    /// while appending that many).
    pub fn reserve(&mut self, extra: usize) {
        self.x.reserve(extra);
        self.v.reserve(extra);
        self.v_prev.reserve(extra);
        self.accel.reserve(extra);
        self.affine.reserve(extra);
        self.f.reserve(extra);
        self.j.reserve(extra);
        self.mass.reserve(extra);
        self.vol0.reserve(extra);
        self.vol.reserve(extra);
        self.stress.reserve(extra);
        self.pressure.reserve(extra);
        self.dev_rate.reserve(extra);
        self.history.reserve(extra);
        self.wave_speed.reserve(extra);
        self.stored_energy.reserve(extra);
        self.material.reserve(extra);
        self.id.reserve(extra);
    }

    /// Drops every particle from slot `n` on (capacity is kept).
    pub fn truncate(&mut self, n: usize) {
        self.x.truncate(n);
        self.v.truncate(n);
        self.v_prev.truncate(n);
        self.accel.truncate(n);
        self.affine.truncate(n);
        self.f.truncate(n);
        self.j.truncate(n);
        self.mass.truncate(n);
        self.vol0.truncate(n);
        self.vol.truncate(n);
        self.stress.truncate(n);
        self.pressure.truncate(n);
        self.dev_rate.truncate(n);
        self.history.truncate(n);
        self.wave_speed.truncate(n);
        self.stored_energy.truncate(n);
        self.material.truncate(n);
        self.id.truncate(n);
    }
}
