//! Particle snapshots: what the maps and animations need of a state
//! (positions, velocity, pressure, acceleration, id), written as legacy VTK
//! for ParaView and read back by the report.

use solver::{StateView, Vec2};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    pub step: u64,
    pub t: f64,
    pub x: Vec<Vec2>,
    pub v: Vec<Vec2>,
    pub pressure: Vec<f64>,
    /// Force-driven |a_p| of the last step (m/s^2).
    pub accel: Vec<f64>,
    pub j: Vec<f64>,
    /// The history variable xi; empty unless a material softens.
    pub history: Vec<f64>,
    pub id: Vec<u32>,
}

impl Snapshot {
    pub fn with_capacity(n: usize) -> Self {
        Snapshot {
            x: Vec::with_capacity(n),
            v: Vec::with_capacity(n),
            pressure: Vec::with_capacity(n),
            accel: Vec::with_capacity(n),
            j: Vec::with_capacity(n),
            id: Vec::with_capacity(n),
            ..Default::default()
        }
    }

    /// Copies the state into this snapshot's buffers (no allocation once sized).
    pub fn capture(&mut self, v: &StateView) {
        self.step = v.step;
        self.t = v.time;
        self.x.clear();
        self.x.extend_from_slice(v.x);
        self.v.clear();
        self.v.extend_from_slice(v.v);
        self.pressure.clear();
        self.pressure.extend_from_slice(v.pressure);
        self.j.clear();
        self.j.extend_from_slice(v.j);
        self.history.clear();
        if v.materials.iter().any(|m| m.softening_strain > 0.0) {
            self.history.extend_from_slice(v.history);
        }
        self.id.clear();
        self.id.extend_from_slice(v.id);
        // The force-driven acceleration the monitor scores.
        self.accel.clear();
        self.accel.extend(v.accel.iter().map(|a| a.norm()));
    }

    pub fn of(v: &StateView) -> Self {
        let mut s = Snapshot::with_capacity(v.x.len());
        s.capture(v);
        s
    }

    /// Legacy ASCII VTK polydata.
    pub fn vtk(&self) -> Vec<u8> {
        use std::fmt::Write;
        let n = self.x.len();
        let mut s = String::with_capacity(n * 120);
        let _ = write!(
            s,
            "# vtk DataFile Version 3.0\nkick particles step {} t {}\nASCII\nDATASET POLYDATA\nPOINTS {n} double\n",
            self.step, self.t
        );
        for x in &self.x {
            let _ = writeln!(s, "{} {} 0", x.x, x.y);
        }
        let _ = writeln!(s, "VERTICES {n} {}", 2 * n);
        for p in 0..n {
            let _ = writeln!(s, "1 {p}");
        }
        let _ = writeln!(s, "POINT_DATA {n}");
        let mut scalar = |name: &str, f: &dyn Fn(usize) -> f64| {
            let _ = writeln!(s, "SCALARS {name} double 1\nLOOKUP_TABLE default");
            for p in 0..n {
                let _ = writeln!(s, "{}", f(p));
            }
        };
        scalar("pressure", &|p| self.pressure[p]);
        scalar("accel", &|p| self.accel[p]);
        scalar("J", &|p| self.j[p]);
        if !self.history.is_empty() {
            scalar("xi", &|p| self.history[p]);
        }
        scalar("id", &|p| self.id[p] as f64);
        let _ = writeln!(s, "VECTORS velocity double");
        for u in &self.v {
            let _ = writeln!(s, "{} {} 0", u.x, u.y);
        }
        s.into_bytes()
    }

    /// Reads what `vtk` wrote.
    pub fn from_vtk(text: &str) -> Result<Snapshot, String> {
        let mut lines = text.lines();
        let title = lines.nth(1).ok_or("empty VTK file")?;
        let mut words = title.split_whitespace();
        let mut snap = Snapshot::default();
        while let Some(w) = words.next() {
            match w {
                "step" => snap.step = words.next().and_then(|v| v.parse().ok()).unwrap_or(0),
                "t" => snap.t = words.next().and_then(|v| v.parse().ok()).unwrap_or(0.0),
                _ => {}
            }
        }
        let nums = |line: &str| -> Result<Vec<f64>, String> {
            line.split_whitespace()
                .map(|w| w.parse::<f64>().map_err(|_| format!("bad number {w:?}")))
                .collect()
        };
        let mut n = 0usize;
        while let Some(line) = lines.next() {
            let mut head = line.split_whitespace();
            match head.next() {
                Some("POINTS") => {
                    n = head
                        .next()
                        .and_then(|v| v.parse().ok())
                        .ok_or("bad POINTS")?;
                    for _ in 0..n {
                        let v = nums(lines.next().ok_or("truncated POINTS")?)?;
                        snap.x.push(Vec2::new(v[0], v[1]));
                    }
                }
                Some("SCALARS") => {
                    let name = head.next().unwrap_or_default().to_string();
                    lines.next();
                    let mut vals = Vec::with_capacity(n);
                    for _ in 0..n {
                        vals.push(nums(lines.next().ok_or("truncated SCALARS")?)?[0]);
                    }
                    match name.as_str() {
                        "pressure" => snap.pressure = vals,
                        "accel" => snap.accel = vals,
                        "J" => snap.j = vals,
                        "xi" => snap.history = vals,
                        "id" => snap.id = vals.iter().map(|v| *v as u32).collect(),
                        _ => {}
                    }
                }
                Some("VECTORS") => {
                    for _ in 0..n {
                        let v = nums(lines.next().ok_or("truncated VECTORS")?)?;
                        snap.v.push(Vec2::new(v[0], v[1]));
                    }
                }
                _ => {}
            }
        }
        if snap.pressure.len() != n || snap.x.len() != n {
            return Err("VTK file lacks points or pressure".into());
        }
        let fill = |v: &mut Vec<f64>, d: f64| {
            if v.len() != n {
                *v = vec![d; n]
            }
        };
        fill(&mut snap.accel, 0.0);
        fill(&mut snap.j, 1.0);
        if snap.history.len() != n {
            snap.history.clear();
        }
        if snap.v.len() != n {
            snap.v = vec![Vec2::zeros(); n];
        }
        Ok(snap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn snapshot(history: Vec<f64>) -> Snapshot {
        Snapshot {
            step: 7,
            t: 0.25,
            x: vec![Vec2::new(0.1, 0.2), Vec2::new(0.3, 0.4)],
            v: vec![Vec2::new(1.0, -1.0), Vec2::new(0.5, 0.0)],
            pressure: vec![10.0, -2.5],
            accel: vec![0.0, 9.81],
            j: vec![1.0, 0.99],
            history,
            id: vec![4, 9],
        }
    }

    /// Every field round-trips through the VTK text; xi is written only for
    /// a softening solid, and a file without it reads back with none.
    #[test]
    fn vtk_round_trips_and_writes_xi_only_when_captured() {
        for history in [vec![0.0, 1.5e-3], vec![]] {
            let s = snapshot(history.clone());
            let text = String::from_utf8(s.vtk()).unwrap();
            assert_eq!(text.contains("SCALARS xi"), !history.is_empty());
            assert_eq!(Snapshot::from_vtk(&text).unwrap(), s);
        }
    }
}
