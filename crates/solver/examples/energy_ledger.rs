//! Where a run's energy budget fails to close: the released water column
//! of studies/energy_booking.toml (0.2 x 0.4 m in a 0.2 m wide box, Tait
//! 1.5 MPa, 0.5 Pa s, quadratic B-splines, USL, dynamic dt), its drift split
//! per stage of every step:
//!
//! - transfers: particles before P2G minus the grid after it, and the
//!   updated grid minus the particles after G2P (the monitor's transfer loss
//!   under APIC and PIC);
//! - gravity: the particles' potential energy change plus gravity's work on
//!   v^{n+1} (zero to round-off when positions move with v^{n+1});
//! - stress against work: the stored and dissipated energy's change (the
//!   remedies' booked changes taken out) plus the grid forces' work on
//!   v^{n+1}, the first half of symplectic Euler's error;
//! - symplectic: -sum m |a|^2 dt^2 / 2 on the grid, the other half, split
//!   by the node's mass against a full node's (< 0.01, < 0.1, < 0.5, more).
//!
//! The drift is the sum of the last three. Usage:
//! `cargo run --release -p kick-solver --example energy_ledger -- apic|pic|flip
//! [REMEDY] [cfl] [t_end]` (docs/findings/energy_booking.md), REMEDY one of
//! `0` (none), a volume relaxation time in seconds, `jbar` (the constant
//! fit) or `jbar-linear`.
//!
//! With a remedy that changes J (J-bar, relaxation) it also replays every
//! step without the remedies from the same state (a clone), so that J_new,
//! the flow's J before the remedy, is known: it prints the booked change
//! W(J_after) - W(J_new) beside the same J change's work at the step's
//! start pressure, -sum p^n V0 (J_after - J_new), the rule by which the
//! forces' work books the flow's own J change, and the drift either way.
//! It also prints the kinetic energy's mean over the run's second half.

use solver::remedies::{j_bar, volume_relaxation};
use solver::*;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let transfer = match args.get(1).map(String::as_str).unwrap_or("apic") {
        "pic" => TransferKind::Pic,
        "flip" => TransferKind::Flip,
        _ => TransferKind::Apic,
    };
    let arg = |i: usize, default: f64| args.get(i).map_or(default, |s| s.parse().unwrap());
    let remedy = args.get(2).cloned().unwrap_or_else(|| "0".into());
    let cfl = arg(3, 0.2);
    let t_end = arg(4, 1.0);

    let mut material = Material::tait(1.5e6);
    material.viscosity = 0.5;
    let material_rho0 = material.rho0;
    // The dam break's column, in a box as wide as the column.
    let mut scene = Scene::dam_break(material);
    scene.size = [0.2, 0.6];
    scene.t_end = t_end;
    let mut method = Method {
        shape: ShapeKind::Bspline2,
        transfer,
        flip_alpha: 1.0,
        scheme: SchemeKind::Usl,
        cfl,
        dt: DtMode::Dynamic,
        ..Method::default()
    };
    match remedy.as_str() {
        "jbar" => method.remedies.j_bar = Some(j_bar::Settings::default()),
        "jbar-linear" => {
            method.remedies.j_bar = Some(j_bar::Settings {
                fit: solver::choices::JBarFit::Linear,
                ..j_bar::Settings::default()
            })
        }
        time => {
            let time: f64 = time
                .parse()
                .expect("REMEDY: 0, a relaxation time, jbar or jbar-linear");
            if time > 0.0 {
                method.remedies.volume_relaxation = Some(volume_relaxation::Settings { time });
            }
        }
    }
    let free_method = Method {
        remedies: Default::default(),
        ..method.clone()
    };
    let gravity = Vec2::new(0.0, -scene.gravity);
    let full_node = material_rho0 * scene.cell * scene.cell;
    let mut s = Solver::new(SolverConfig {
        scene,
        method,
        perturb: vec![],
    })
    .expect("valid config");

    let (mut p2g, mut g2p, mut gravity_part, mut stress_part) = (0.0, 0.0, 0.0, 0.0);
    let mut symplectic = [0.0f64; 4];
    let mut booked_total = 0.0;
    let changes_j = remedy != "0";
    let water_area: f64 = s.view().volume0.iter().sum();
    // Sums over steps: the remedy's J change at the start pressure, its
    // exact stored change, and sum V0 (J_after - J_new)^2.
    let (mut at_start_pressure, mut exact, mut squared) = (0.0, 0.0, 0.0);
    let mut pressure_before = Vec::new();
    // The kinetic energy's mean over the last half of the run.
    let (mut late_kinetic, mut late_steps) = (0.0, 0.0);
    while !s.finished() {
        let before = s.energy();
        let dt = s.next_dt().min(t_end - s.time());
        let free = changes_j.then(|| {
            let mut free = s.clone();
            free.set_method(free_method.clone()).unwrap();
            free.step_with_dt(dt).unwrap();
            free
        });
        pressure_before.clear();
        pressure_before.extend_from_slice(s.view().pressure);
        s.step_with_dt(dt).unwrap();
        let booked: f64 = s.remedy_energy().map(|(_, e)| e.total()).sum();
        booked_total += booked;
        if let Some(free) = &free {
            let (a, b) = (s.view(), free.view());
            exact += a.energy.stored - b.energy.stored;
            let j_free = b.j.iter();
            for (((&j, j_free), &v0), &p0) in
                a.j.iter().zip(j_free).zip(a.volume0).zip(&pressure_before)
            {
                let dj = j - j_free;
                at_start_pressure -= p0 * v0 * dj;
                squared += v0 * dj * dj;
            }
        }
        let v = s.view();
        let after = v.energy;
        if v.time > 0.5 * t_end {
            late_kinetic += after.kinetic_with_affine();
            late_steps += 1.0;
        }
        p2g += v.ke_particles_p2g - v.ke_grid_p2g;
        g2p += v.ke_grid_updated - after.kinetic_with_affine();
        let (mut gravity_work, mut force_work) = (0.0, 0.0);
        let g = v.grid;
        for &n in g.active {
            let n = n as usize;
            let (m, v1, a) = (g.mass_raw[n], g.velocity[n], g.acceleration[n]);
            gravity_work += m * gravity.dot(&v1) * v.dt;
            force_work += m * (a - gravity).dot(&v1) * v.dt;
            let share = g.mass[n] / full_node;
            let class = [0.01, 0.1, 0.5, f64::INFINITY]
                .iter()
                .position(|&limit| share < limit)
                .unwrap();
            symplectic[class] -= 0.5 * m * a.norm_squared() * v.dt * v.dt;
        }
        gravity_part += after.gravitational - before.gravitational + gravity_work;
        stress_part += after.stored - before.stored - booked + after.dissipated - before.dissipated
            + force_work;
    }
    let drift = gravity_part + stress_part + symplectic.iter().sum::<f64>();
    println!(
        "{transfer:?}, remedy {remedy}, CFL {cfl}, to {t_end} s, {} steps (J/m)",
        s.view().step
    );
    println!("drift                     {drift:+.4e}");
    println!("  gravity                 {gravity_part:+.4e}");
    println!("  stress against work     {stress_part:+.4e}");
    println!(
        "  symplectic by node mass {:+.4e} (< 0.01 full) {:+.4e} (< 0.1) {:+.4e} (< 0.5) {:+.4e} (more)",
        symplectic[0], symplectic[1], symplectic[2], symplectic[3]
    );
    println!("transfer losses           {p2g:.4e} (P2G) {g2p:.4e} (G2P)");
    println!("remedies' booked change   {booked_total:+.4e}");
    println!(
        "kinetic energy, mean over the second half {:.4e}",
        late_kinetic / late_steps
    );
    if changes_j {
        let steps = s.view().step as f64;
        println!("J change against the run without remedies, summed over steps:");
        println!("  stored, exact           {exact:+.4e}");
        println!("  at the start pressure   {at_start_pressure:+.4e}");
        println!(
            "  drift were it booked so {:+.4e}",
            drift + booked_total - at_start_pressure
        );
        println!(
            "  rms J change per step   {:.4e} (sum V0 dJ^2 over steps {squared:.4e})",
            (squared / steps / water_area).sqrt()
        );
    }
}
