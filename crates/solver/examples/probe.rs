use solver::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let shape = match args.get(1).map(|s| s.as_str()).unwrap_or("bspline2") {
        "linear" => ShapeKind::Linear,
        "gimp" => ShapeKind::Gimp,
        "bspline3" => ShapeKind::Bspline3,
        _ => ShapeKind::Bspline2,
    };
    let transfer = match args.get(2).map(|s| s.as_str()).unwrap_or("pic") {
        "flip" => TransferKind::Flip,
        "apic" => TransferKind::Apic,
        _ => TransferKind::Pic,
    };
    let k: f64 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(1.5e5);
    let t_end: f64 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(1.0);
    let mut mat = Material::tait(k);
    mat.eos = EosKind::Power;
    mat.gamma = 7.0;
    let mut scene = Scene::dam_break(mat);
    scene.t_end = t_end;
    let mut method = Method::baseline();
    method.shape = shape;
    method.transfer = transfer;
    if let Ok(c) = std::env::var("CFL") {
        method.cfl = c.parse().unwrap();
    }
    if let Ok(c) = std::env::var("SCHEME") {
        method.scheme = match c.as_str() {
            "usl" => SchemeKind::Usl,
            "musl" => SchemeKind::Musl,
            _ => SchemeKind::Usf,
        };
    }
    let mut s = Solver::new(SolverConfig {
        scene,
        method,
        perturb: vec![],
    })
    .unwrap();
    let e0 = s.energy().total();
    let mut emin = e0;
    let mut inj: f64 = 0.0;
    let t0 = std::time::Instant::now();
    let mut next = 0.0;
    while !s.finished() {
        if let Err(e) = s.step() {
            println!("error {e}");
            break;
        }
        let e = s.energy().total();
        emin = emin.min(e);
        inj = inj.max(e - emin);
        let v = s.view();
        if v.n_outside > 0 || v.n_nonfinite > 0 {
            println!(
                "blew up at step {} t {} out {} nonfinite {}",
                v.step, v.time, v.n_outside, v.n_nonfinite
            );
            break;
        }
        if s.time() >= next {
            next += 0.1;
            let vmax = v.v.iter().map(|x| x.norm()).fold(0.0, f64::max);
            let xmax = v.x.iter().map(|x| x.x).fold(0.0, f64::max);
            println!("t {:.3} step {} dt {:.2e} E {:.4} ek {:.3} inj {:.3e} cour {:.3} vmax {:.3} xmax {:.3} jmin {:.3}", v.time, v.step, v.dt, e, v.energy.kinetic, inj, v.courant, vmax, xmax, v.j.iter().cloned().fold(9.0, f64::min));
        }
    }
    let n = s.particle_count() as f64 * s.step_count() as f64;
    println!(
        "E0 {e0} final {} wall {:.2}s  {:.2} M pstep/s",
        s.energy().total(),
        t0.elapsed().as_secs_f64(),
        n / t0.elapsed().as_secs_f64() / 1e6
    );
}
