//! EOS forms of docs/physics.md section 2: U' = -p and K_t = -J dp/dJ by finite
//! differences, signs (compression positive), the inverse, and J_res.

use solver::{EosKind, Material};

fn materials() -> Vec<Material> {
    let mut out = vec![];
    for (eos, gamma) in [
        (EosKind::Power, 1.0),
        (EosKind::Power, 4.0),
        (EosKind::Power, 7.0),
        (EosKind::Tait, 7.0),
        (EosKind::Linear, 1.0),
    ] {
        let mut m = Material::tait(1.5e6);
        m.eos = eos;
        m.gamma = gamma;
        out.push(m);
    }
    out
}

#[test]
fn derivatives_match_finite_differences() {
    for m in materials() {
        for k in 0..50 {
            let j = 0.7 + 0.012 * k as f64;
            let e = 1e-6;
            let s = m.eos(j);
            let (up, dn) = (m.eos(j + e), m.eos(j - e));
            let du = (up.energy - dn.energy) / (2.0 * e);
            let dp = (up.pressure - dn.pressure) / (2.0 * e);
            let scale = m.k * (1.0 + s.tangent_modulus / m.k);
            assert!(
                (du + s.pressure).abs() < 1e-6 * scale,
                "{:?} U' != -p at J {j}",
                m.eos
            );
            assert!(
                (-j * dp - s.tangent_modulus).abs() < 1e-6 * scale,
                "{:?} K_t at J {j}: {} vs {}",
                m.eos,
                -j * dp,
                s.tangent_modulus
            );
        }
    }
}

#[test]
fn signs_zero_point_and_inverse() {
    for m in materials() {
        let s = m.eos(1.0);
        assert!(s.pressure.abs() < 1e-9 && s.energy.abs() < 1e-9);
        assert!(
            m.eos(0.9).pressure > 0.0,
            "compression gives positive pressure"
        );
        assert!(m.eos(1.1).pressure < 0.0, "expansion gives tension");
        assert!(m.eos(0.9).energy > 0.0 && m.eos(1.1).energy > 0.0);
        for p in [-1e4, 0.0, 3.9e3, 1e5] {
            let j = m.j_at_pressure(p);
            assert!(
                (m.eos(j).pressure - p).abs() < 1e-6 * m.k,
                "{:?} inverse at {p}",
                m.eos
            );
        }
    }
}

#[test]
fn tangent_modulus_values_from_physics_md() {
    let mut m = Material::tait(1.0);
    m.eos = EosKind::Tait;
    // docs/physics.md: Tait at J = 0.81 is about 6.8 K.
    let kt = m.eos(0.81).tangent_modulus;
    assert!((kt - 0.81 * (0.19f64 / 0.0894).exp()).abs() < 1e-12);
    assert!((kt - 6.8).abs() < 0.1, "{kt}");
    m.eos = EosKind::Power;
    m.gamma = 7.0;
    assert!((m.eos(1.0).tangent_modulus - 7.0).abs() < 1e-12);
}

#[test]
fn thermal_jres_and_tension_cutoff() {
    let mut m = Material::tait(1.5e6);
    m.j_res = 1.02;
    assert!(
        m.eos(1.02).pressure.abs() < 1e-9,
        "free thermal expansion is stress free"
    );
    assert_eq!(
        m.eos(0.99).pressure,
        Material::tait(1.5e6).eos(0.99 / 1.02).pressure
    );
    m.pressure_floor = Some(-100.0);
    assert_eq!(m.pressure(1.2), -100.0);
    assert_eq!(m.pressure(0.99), m.eos(0.99).pressure);
}

/// The vectorised run over many particles gives the bits of the EOS called
/// particle by particle, for every form, with and without cutoff and J_res,
/// down to J near 0 (overflow) and non-finite J.
#[test]
fn eval_run_matches_eos_bit_for_bit() {
    let mut js: Vec<f64> = (0..997).map(|k| 0.002 + 0.0031 * k as f64).collect();
    js.extend([0.0, 1e-300, f64::NAN, f64::INFINITY, -0.5, 1.0]);
    let vol0: Vec<f64> = (0..js.len())
        .map(|k| 1e-4 * (1.0 + k as f64 * 1e-3))
        .collect();
    let mut cases = materials();
    for (eos, gamma) in [(EosKind::Power, 2.5), (EosKind::Power, 16.0)] {
        let mut m = Material::tait(1.5e6);
        m.eos = eos;
        m.gamma = gamma;
        cases.push(m);
    }
    for base in cases {
        for (j_res, floor) in [
            (1.0, None),
            (1.02, None),
            (1.0, Some(-1e3)),
            (0.97, Some(0.0)),
        ] {
            let mut m = base.clone();
            m.j_res = j_res;
            m.pressure_floor = floor;
            let n = js.len();
            let (mut p, mut c, mut u) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            m.eval_run(&js, &vol0, (&mut p, &mut c, &mut u));
            for k in 0..n {
                let s = m.eos(js[k]);
                let what = format!(
                    "{:?} gamma {} J {} j_res {j_res} floor {floor:?}",
                    m.eos, m.gamma, js[k]
                );
                assert_eq!(p[k].to_bits(), m.cut(s.pressure).to_bits(), "p: {what}");
                assert_eq!(
                    c[k].to_bits(),
                    m.wave_speed_of(&s, js[k]).to_bits(),
                    "c: {what}"
                );
                let stored = vol0[k] * m.energy_of(js[k], &s);
                assert_eq!(u[k].to_bits(), stored.to_bits(), "U: {what}");
            }
        }
    }
}

/// Under a tension cutoff the stored energy is the work of the cut
/// pressure: U_cut(J) = -int_1^J max(p, floor) dJ', in J / j_res (Simpson's rule on a
/// fine grid), so U_cut' = -p_cut, continuous at the cut, and the EOS's own
/// U where nothing is cut (to the bit when the floor is at most 0). Floors
/// at 0 (the bug report's "no tension"), in tension, and above 0; with J_res.
#[test]
fn the_stored_energy_under_a_tension_cutoff_is_the_cut_pressures_work() {
    for base in materials() {
        for (floor, j_res) in [(0.0, 1.0), (-0.01, 1.0), (0.002, 1.0), (0.0, 1.02)] {
            let mut m = base.clone();
            m.pressure_floor = Some(floor * m.k);
            m.j_res = j_res;
            let p_cut = |j: f64| m.pressure(j);
            let what = |j: f64| {
                format!(
                    "{:?} gamma {} floor {floor} K, j_res {j_res}, J {j}",
                    m.eos, m.gamma
                )
            };
            for k in 0..=40 {
                let j = 0.8 + 0.01 * k as f64;
                let n = 2000;
                // U is a function of J / j_res (docs/physics.md section 2).
                let dx = (j / j_res - 1.0) / n as f64;
                let simpson: f64 = (0..=n)
                    .map(|i| {
                        let w = if i == 0 || i == n {
                            1.0
                        } else if i % 2 == 1 {
                            4.0
                        } else {
                            2.0
                        };
                        w * p_cut(j_res * (1.0 + dx * i as f64))
                    })
                    .sum::<f64>()
                    * dx
                    / 3.0;
                let u = m.stored(j);
                // The cut leaves a kink, which Simpson's rule meets at O(dx^2).
                assert!(
                    (u + simpson).abs() < 1e-7 * m.k,
                    "{}: {u} vs {}",
                    what(j),
                    -simpson
                );
                if floor <= 0.0 && m.eos(j).pressure >= floor * m.k {
                    assert_eq!(u.to_bits(), m.eos(j).energy.to_bits(), "{}", what(j));
                }
            }
        }
        let mut m = base.clone();
        m.pressure_floor = Some(0.0);
        assert!(
            m.stored(1.1) < m.eos(1.1).energy,
            "{:?}: no stored energy in cut tension",
            m.eos
        );
        assert!(
            m.stored(1.1).abs() < 1e-12 * m.k,
            "{:?}: a floor at 0 stores nothing in expansion",
            m.eos
        );
    }
}
