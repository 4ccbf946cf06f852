//! Runs a dam break under the monitor and prints what it sees.
//! usage: watch SHAPE TRANSFER EOS K T_END [PERTURB_STEP]
use monitor::{Monitor, MonitorConfig};
use solver::*;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let shape: ShapeKind = serde_json_like(&a[1]);
    let transfer: TransferKind = serde_json_like(&a[2]);
    let mut mat = Material::tait(a[4].parse().unwrap());
    mat.eos = if a[3] == "tait" {
        EosKind::Tait
    } else {
        EosKind::Power
    };
    mat.gamma = 7.0;
    let mut scene = Scene::dam_break(mat);
    scene.t_end = a[5].parse().unwrap();
    let mut method = Method::baseline();
    method.shape = shape;
    method.transfer = transfer;
    let mut s = Solver::new(SolverConfig {
        scene,
        method,
        perturb: vec![],
    })
    .unwrap();
    let mut cfgm = MonitorConfig::default();
    if std::env::var("NOJUMP").is_ok() {
        cfgm.jump_speed = 1e9;
    }
    let mut m = Monitor::new(cfgm, &s.view());
    let (mut za, mut aa) = (0.0f64, 0.0f64);
    let mut next = 0.0;
    let t0 = std::time::Instant::now();
    let mut tmon = 0.0;
    while !s.finished() {
        if let Err(e) = s.step() {
            println!("{e}");
            break;
        }
        let tm = std::time::Instant::now();
        let r = m.observe(&s.view()).clone();
        tmon += tm.elapsed().as_secs_f64();
        za = za.max(r.max_jump);
        aa = aa.max(r.max_accel_g);
        if r.events_opened > 0 {
            for e in &m.events()[m.events().len() - r.events_opened..] {
                println!("EVENT {} {:?} step {} t {:.4} cells {:?} a/g {:.1} jump {:.3} m/s rules {:?} q {} d {} courant {:.2}", e.id, e.kind, e.first_step, e.t, e.cells, e.peak_accel_g, e.jump_speed, e.rules.names(), e.quiescent_before, e.previously_deformed(), e.courant);
            }
        }
        if r.blow_out.is_some() {
            println!("BLOW {:?}", r.blow_out);
            break;
        }
        if r.t >= next {
            next += 0.1;
            let f = m.field_metrics(&s.view());
            println!("t {:.2} max jump {:.3} maxa {:.1}g inj {:.3e} floor {:.2e} cb {:?} hydro {:.3} front {:?} cour {:.2}", r.t, za, aa, r.energy_injected, r.injection_floor, f.checkerboard_nodal.map(|c| (c*1000.0).round()/1000.0), f.hydro_rel_rms, f.front_z, r.courant);
            za = 0.0;
            aa = 0.0;
        }
    }
    let total = t0.elapsed().as_secs_f64();
    println!(
        "wall {total:.2}s monitor {tmon:.2}s ({:.1}%) events {}",
        100.0 * tmon / (total - tmon),
        m.events().len()
    );
}
fn serde_json_like<T: serde::de::DeserializeOwned>(s: &str) -> T {
    serde::Deserialize::deserialize(
        serde::de::value::StrDeserializer::<serde::de::value::Error>::new(s),
    )
    .unwrap()
}
