//! The monitor's deformation-rate signal is the in-plane deviator.

use solver::viscosity::{in_plane_dev_rate, newtonian};
use solver::Mat2;

#[test]
fn in_plane_compression_has_no_deviatoric_rate() {
    // D = diag(d, d): isotropic in plane; the 3D deviator would give sqrt(2/3) d.
    let d = Mat2::new(-3.0, 0.0, 0.0, -3.0);
    assert_eq!(in_plane_dev_rate(&d), 0.0);
    assert_eq!(newtonian(1.0, &d).dev_rate, 0.0);
    // The viscous stress still sees the out-of-plane deviator (plane strain).
    let s = newtonian(1.0, &d).stress;
    assert!((s[(0, 0)] - 2.0 * (-3.0 + 2.0)).abs() < 1e-12, "{s}");
}

#[test]
fn simple_shear_and_pure_shear_rates() {
    // Simple shear v_x = g y: D_xy = g / 2, |dev D| = g / sqrt 2.
    let g = 4.0;
    let d = Mat2::new(0.0, g / 2.0, g / 2.0, 0.0);
    assert!((in_plane_dev_rate(&d) - g / 2f64.sqrt()).abs() < 1e-12);
    // Pure shear diag(e, -e): |dev D| = sqrt 2 e, unchanged by an added dilatation.
    let e = 1.5;
    let pure = Mat2::new(e, 0.0, 0.0, -e);
    let dilated = pure + 7.0 * Mat2::identity();
    assert!((in_plane_dev_rate(&pure) - 2f64.sqrt() * e).abs() < 1e-12);
    assert!((in_plane_dev_rate(&dilated) - in_plane_dev_rate(&pure)).abs() < 1e-12);
}
