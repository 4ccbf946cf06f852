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
    /// EOS figures of the current J, cached by the stress stage so the time
    /// step and the energy need no second EOS evaluation: c(J) and V0 U(J).
    pub wave_speed: Vec<f64>,
    pub stored_energy: Vec<f64>,
    pub material: Vec<u16>,
    pub id: Vec<u32>,
}

impl Particles {
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
        self.affine.push(Mat2::zeros());
        self.f.push(Mat2::identity());
        self.j.push(1.0);
        self.mass.push(mass);
        self.vol0.push(vol0);
        self.vol.push(vol0);
        self.stress.push(Mat2::zeros());
        self.pressure.push(0.0);
        self.dev_rate.push(0.0);
        self.wave_speed.push(0.0);
        self.stored_energy.push(0.0);
        self.material.push(material);
        self.id.push(id);
    }
}
