//! How deep below a flat free surface a cell's centre lies, read from the
//! grid's fluid fraction (`method.projection.surface_level = "distance"`).
//!
//! A node's mass is its kernel's integral over the water, so a node s
//! cells below a flat surface reads the kernel's cumulative F(s), and a
//! cell (the mean of its corners) G(s) = (F(s + 1/2) + F(s - 1/2)) / 2.
//! G(0) = 1/2, so the fraction's half marks the surface; but G is a smooth
//! step, not a line, so a fraction interpolated linearly between two cell
//! centres places a surface that moves unlike the water between them
//! (under quadratic B-splines 9 % less near a cell's edge, up to 20 %
//! more near a centre). Inverting G reads the depth itself, exact for a
//! flat surface along a grid axis whatever its height in the cell.

use crate::choices::ShapeKind;

/// The depths read, in cells: a fluid cell beside an air cell lies within
/// a cell of the surface; a cell further in or out reads this bound.
pub const DEPTH_BOUND: f64 = 1.5;

/// Halvings of the bracket [-DEPTH_BOUND, DEPTH_BOUND]: 3 / 2^44 < 1e-12.
const BISECTIONS: u32 = 44;

/// The share of the hat that lies more than `s >= 0` cells beyond its
/// node: 1/2 - (F(s) - 1/2). GIMP (uGIMP and cpGIMP) spreads the
/// particles' mass over their domains and integrates the hat, so a
/// continuum of them reads the hat's.
fn hat_tail(s: f64) -> f64 {
    let d = (1.0 - s).max(0.0);
    0.5 * d * d
}

/// The quadratic B-spline's tail, as `hat_tail`.
fn quadratic_tail(s: f64) -> f64 {
    if s < 0.5 {
        0.5 - 0.75 * s + s * s * s / 3.0
    } else {
        let d = (1.5 - s).max(0.0);
        d * d * d / 6.0
    }
}

/// The cubic B-spline's tail, as `hat_tail`.
fn cubic_tail(s: f64) -> f64 {
    if s < 1.0 {
        0.5 - 2.0 * s / 3.0 + s * s * s / 3.0 - s * s * s * s / 8.0
    } else {
        let d = (2.0 - s).max(0.0);
        d * d * d * d / 24.0
    }
}

/// The kernel's tail; matched once per call of `depth_of`, so that its
/// bisection runs on one kernel's arithmetic.
fn tail_of(basis: ShapeKind) -> fn(f64) -> f64 {
    match basis {
        ShapeKind::Linear | ShapeKind::Gimp | ShapeKind::Cpgimp | ShapeKind::Cpdi => hat_tail,
        ShapeKind::Bspline2 => quadratic_tail,
        ShapeKind::Bspline3 => cubic_tail,
    }
}

/// F(s): the share of a node's kernel below a flat surface `s` cells above
/// the node (s < 0: the node is above the surface).
fn node_fraction(tail: impl Fn(f64) -> f64, s: f64) -> f64 {
    if s >= 0.0 {
        1.0 - tail(s)
    } else {
        tail(-s)
    }
}

/// G(s) under `tail`'s kernel.
fn fraction_by(tail: impl Fn(f64) -> f64 + Copy, s: f64) -> f64 {
    0.5 * (node_fraction(tail, s + 0.5) + node_fraction(tail, s - 0.5))
}

/// G(s): the fluid fraction of a cell whose centre lies `s` cells below a
/// flat surface along a grid axis.
pub fn cell_fraction(basis: ShapeKind, s: f64) -> f64 {
    fraction_by(tail_of(basis), s)
}

/// G^-1: the depth in cells, within +-`DEPTH_BOUND`, at which a cell reads
/// `fraction`, by bisection (G increases; a fixed count of halvings, so
/// the result is the same on every machine).
pub fn depth_of(basis: ShapeKind, fraction: f64) -> f64 {
    match basis {
        ShapeKind::Linear | ShapeKind::Gimp | ShapeKind::Cpgimp | ShapeKind::Cpdi => {
            depth_by(hat_tail, fraction)
        }
        ShapeKind::Bspline2 => depth_by(quadratic_tail, fraction),
        ShapeKind::Bspline3 => depth_by(cubic_tail, fraction),
    }
}

/// `depth_of` under `tail`'s kernel (one copy per kernel).
fn depth_by(tail: impl Fn(f64) -> f64 + Copy, fraction: f64) -> f64 {
    invert(|s| fraction_by(tail, s), fraction)
}

/// The share theta of the way from a fluid cell's centre to its air
/// neighbour's at which a flat surface gives the face between them (a
/// quadratic B-spline's node, as the staggered faces are) the fill
/// `fill`: half a cell plus the surface's height above the face,
/// F^-1(fill), within [0, 1].
pub fn face_share(fill: f64) -> f64 {
    (0.5 + invert(|s| node_fraction(quadratic_tail, s), fill)).clamp(0.0, 1.0)
}

/// The s within +-`DEPTH_BOUND` at which the increasing `reading` gives
/// `value`, by bisection (a fixed count of halvings, so the result is
/// the same on every machine). Halvings whose test is certain, beyond a
/// window about a secant estimate of the root, skip the reading: the
/// result is the plain bisection's to the bit, at a third of its
/// readings.
fn invert(reading: impl Fn(f64) -> f64, value: f64) -> f64 {
    let (mut lo, mut hi) = (-DEPTH_BOUND, DEPTH_BOUND);
    let (at_lo, at_hi) = (reading(lo), reading(hi));
    if value <= at_lo {
        return lo;
    }
    if value >= at_hi {
        return hi;
    }
    let window = certain_window(&reading, value, at_lo, at_hi);
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        let below = match window {
            Some((a, _)) if mid <= a => true,
            Some((_, b)) if mid >= b => false,
            _ => reading(mid) < value,
        };
        if below {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Half the width of the window `invert` reads within.
const WINDOW: f64 = 1e-12;

/// A bound on a reading's rounding error: the tails are polynomials of
/// degree at most 4 in |s| < 3 with values within [0, 1], a few ulp of 1.
const READING_ROUNDING: f64 = 1e-14;

/// Illinois steps at most, from the bracket [-DEPTH_BOUND, DEPTH_BOUND].
const SECANT_STEPS: u32 = 24;

/// (a, b) about the root such that every s <= a reads below `value` and
/// every s >= b reads above it, whatever the rounding (each end read
/// once with `READING_ROUNDING` to spare, the reading monotone): then a
/// halving's test is known without reading. None where the secant does
/// not settle (a flat tail): `invert` then reads at every halving.
fn certain_window(
    reading: &impl Fn(f64) -> f64,
    value: f64,
    at_lo: f64,
    at_hi: f64,
) -> Option<(f64, f64)> {
    let (mut a, mut fa) = (-DEPTH_BOUND, at_lo - value);
    let (mut b, mut fb) = (DEPTH_BOUND, at_hi - value);
    let mut root = 0.5 * (a + b);
    let mut last_side = 0;
    for _ in 0..SECANT_STEPS {
        root = (a * fb - b * fa) / (fb - fa);
        let f = reading(root) - value;
        if f.abs() <= 0.1 * READING_ROUNDING {
            break;
        }
        // Illinois: halve the kept end's value when the same end moves
        // twice, so that the bracket closes from both sides.
        if f < 0.0 {
            (a, fa) = (root, f);
            if last_side < 0 {
                fb *= 0.5;
            }
            last_side = -1;
        } else {
            (b, fb) = (root, f);
            if last_side > 0 {
                fa *= 0.5;
            }
            last_side = 1;
        }
    }
    let (a, b) = (root - WINDOW, root + WINDOW);
    (reading(a) < value - READING_ROUNDING && reading(b) > value + READING_ROUNDING)
        .then_some((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::{bspline, linear};

    const BASES: [ShapeKind; 3] = [ShapeKind::Linear, ShapeKind::Bspline2, ShapeKind::Bspline3];

    fn kernel(basis: ShapeKind, r: f64) -> f64 {
        match basis {
            ShapeKind::Bspline2 => bspline::quadratic(r).0,
            ShapeKind::Bspline3 => bspline::cubic(r).0,
            _ => linear::kernel(r).0,
        }
    }

    /// F is the kernel's cumulative: its slope is the kernel (central
    /// differences against the shapes' own kernels), and it runs 0 to 1.
    #[test]
    fn a_nodes_fraction_is_its_kernels_cumulative() {
        for basis in BASES {
            let tail = tail_of(basis);
            assert_eq!(node_fraction(tail, -2.5), 0.0, "{basis:?}");
            assert_eq!(node_fraction(tail, 2.5), 1.0, "{basis:?}");
            assert!((node_fraction(tail, 0.0) - 0.5).abs() < 1e-15, "{basis:?}");
            let e = 1e-6;
            for k in 0..=80 {
                let s = -2.0 + 0.05 * k as f64 + 0.013;
                let slope = (node_fraction(tail, s + e) - node_fraction(tail, s - e)) / (2.0 * e);
                let n = kernel(basis, s);
                assert!(
                    (slope - n).abs() < 1e-8,
                    "{basis:?} at {s}: {slope} against {n}"
                );
            }
        }
    }

    /// The depth read back from a cell's fraction is the depth it was
    /// made at, across a cell either side of the surface; linear
    /// interpolation of the fraction between two centres straddling a
    /// surface a quarter cell from an edge places it 0.017 cells short
    /// (the error this mapping removes).
    #[test]
    fn the_depth_read_from_a_fraction_is_the_surfaces() {
        for basis in BASES {
            for k in 0..=40 {
                let s = -1.0 + 0.05 * k as f64;
                let back = depth_of(basis, cell_fraction(basis, s));
                assert!((back - s).abs() < 1e-11, "{basis:?}: {s} read as {back}");
            }
            assert_eq!(depth_of(basis, 1.2), DEPTH_BOUND);
            assert_eq!(depth_of(basis, -0.1), -DEPTH_BOUND);
        }
        let g = |s| cell_fraction(ShapeKind::Bspline2, s) - 0.5;
        let (inside, outside) = (g(0.75), g(-0.25));
        let linear = inside / (inside - outside);
        assert!(0.75 - linear > 0.015, "linear theta {linear}");
    }

    /// A face s cells below a flat surface holds F(s) of a full face's
    /// mass; its share reads the surface back half a cell plus s from its
    /// fluid cell's centre, and clamps to [0, 1] beyond.
    #[test]
    fn a_faces_share_reads_a_flat_surface() {
        for k in 0..=18 {
            let s = -0.45 + 0.05 * k as f64;
            let share = face_share(node_fraction(quadratic_tail, s));
            assert!((share - (0.5 + s)).abs() < 1e-11, "{s} read as {share}");
        }
        assert_eq!(face_share(0.0), 0.0);
        assert_eq!(face_share(1.0), 1.0);
    }

    /// The bisection every reading tests, as `invert` ran before the
    /// window.
    fn plain_bisection(reading: impl Fn(f64) -> f64, value: f64) -> f64 {
        let (mut lo, mut hi) = (-DEPTH_BOUND, DEPTH_BOUND);
        if value <= reading(lo) {
            return lo;
        }
        if value >= reading(hi) {
            return hi;
        }
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if reading(mid) < value {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// The window skips readings, never changes a result: every kernel's
    /// cell depth and the face's share match the plain bisection to the
    /// bit across the whole range of fractions, in under half its
    /// readings.
    #[test]
    fn the_windowed_bisection_is_the_plain_ones_to_the_bit() {
        let readings = std::cell::Cell::new(0usize);
        let mut calls = 0;
        for basis in BASES {
            let tail = tail_of(basis);
            let counted = |s: f64| {
                readings.set(readings.get() + 1);
                fraction_by(tail, s)
            };
            for k in 0..=4000 {
                let value = -0.01 + 1.02 * (k as f64 + 0.37) / 4000.0;
                let fast = invert(counted, value);
                let plain = plain_bisection(|s| fraction_by(tail, s), value);
                assert_eq!(fast.to_bits(), plain.to_bits(), "{basis:?} at {value}");
                calls += 1;
            }
        }
        for k in 0..=4000 {
            let fill = (k as f64 + 0.5) / 4001.0;
            let plain = plain_bisection(|s| node_fraction(quadratic_tail, s), fill);
            let fast = invert(|s| node_fraction(quadratic_tail, s), fill);
            assert_eq!(fast.to_bits(), plain.to_bits(), "face fill {fill}");
        }
        let mean = readings.get() as f64 / calls as f64;
        assert!(mean < 20.0, "{mean} readings a call against the plain 46");
    }
}
