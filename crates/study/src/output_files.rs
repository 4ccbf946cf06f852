//! Atomic file writes (temp file + rename) and the VTK particle format.

use solver::StateView;
use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` through a temporary sibling and a rename, so a
/// reader never sees a half-written file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path)
}

/// Legacy ASCII VTK polydata of the particles (ParaView opens it directly).
pub fn vtk_particles(v: &StateView) -> Vec<u8> {
    let n = v.x.len();
    let mut s = String::with_capacity(n * 160);
    s.push_str("# vtk DataFile Version 3.0\n");
    s.push_str(&format!(
        "kick particles step {} t {}\nASCII\nDATASET POLYDATA\n",
        v.step, v.time
    ));
    s.push_str(&format!("POINTS {n} double\n"));
    for x in v.x {
        s.push_str(&format!("{} {} 0\n", x.x, x.y));
    }
    s.push_str(&format!("VERTICES {n} {}\n", 2 * n));
    for p in 0..n {
        s.push_str(&format!("1 {p}\n"));
    }
    s.push_str(&format!("POINT_DATA {n}\n"));
    let scalar = |s: &mut String, name: &str, f: &dyn Fn(usize) -> f64| {
        s.push_str(&format!("SCALARS {name} double 1\nLOOKUP_TABLE default\n"));
        for p in 0..n {
            s.push_str(&format!("{}\n", f(p)));
        }
    };
    scalar(&mut s, "pressure", &|p| v.pressure[p]);
    scalar(&mut s, "J", &|p| v.j[p]);
    scalar(&mut s, "dev_rate", &|p| v.dev_rate[p]);
    scalar(&mut s, "id", &|p| v.id[p] as f64);
    let accel = |p: usize| (v.v[p] - v.v_prev[p]).norm() / v.dt.max(1e-300);
    scalar(&mut s, "accel", &accel);
    s.push_str("VECTORS velocity double\n");
    for u in v.v {
        s.push_str(&format!("{} {} 0\n", u.x, u.y));
    }
    s.into_bytes()
}
