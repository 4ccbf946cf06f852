//! Fault injection (`[[perturb]]`): a velocity impulse added after G2P to
//! the particles of a region, at a step or at a time, in a region given in
//! metres or placed relative to the state at that time (in the bulk, at the
//! free surface, beside a wall), with dv given or relative to the local
//! flow (along it, against it, upward). The impulse is part of the
//! particles' force-driven acceleration (dv / dt). Each applied impulse is
//! recorded as resolved (`Planted`): the calibration of the detector reads
//! where and when it was.

use crate::config_error::{check, ordered_rect, ConfigError};
use crate::particles::{Particles, Vec2};
use serde::{Deserialize, Serialize};

/// Where a placed patch goes, relative to the fluid at the plant time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// Every cell within `MARGIN` cells of the patch holds fluid, and the
    /// patch is at least `MARGIN` cells from every wall.
    Bulk,
    /// The patch's cells hold fluid and the row above it none (the free
    /// surface), at least `MARGIN` cells from the side walls.
    Surface,
    /// Against a side wall, with fluid within `MARGIN` cells elsewhere
    /// and at least `MARGIN` cells above the floor.
    Wall,
}

/// The direction of a relative impulse.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Along the patch's mean velocity (+x when it is at rest).
    Along,
    /// Against it.
    Against,
    /// Upward, against gravity.
    Up,
}

/// Cells a placed patch keeps from the surface and the walls.
pub const MARGIN: usize = 3;

/// The box a patch is placed in: its lower-left corner and size (m), its
/// cell size and its cells per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub origin: [f64; 2],
    pub size: [f64; 2],
    pub cell: f64,
    pub cells: [usize; 2],
}

/// A `[[perturb]]` entry: when (`step` or `t`), where (`region` or
/// `place`, `cells`, `near`) and how much (`dv`, or `speed` and
/// `direction`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Perturb {
    /// The step (>= 1) whose G2P is followed by the impulse ...
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<u64>,
    /// ... or the time (s): the step that starts at or before it and ends after it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t: Option<f64>,
    /// [x0, y0, x1, y1] in metres ...
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<[f64; 4]>,
    /// ... or a patch of `cells` x `cells` grid cells placed at the plant time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub place: Option<Placement>,
    #[serde(default = "Perturb::one_cell")]
    pub cells: usize,
    /// The placed patch nearest this point (metres; default the box's centre).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub near: Option<[f64; 2]>,
    /// A placed patch holds at least this many particles (with `place`
    /// only; default: any cell holding one is fluid). A patch of fewer than a detector's
    /// cluster minimum is below its resolution, so calibrating with one
    /// measures the packing, not the detector.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_particles: Option<usize>,
    /// The velocity added (m/s) ...
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dv: Option<[f64; 2]>,
    /// ... or its size (m/s) and direction relative to the flow.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<Direction>,
    /// The velocity spread evenly over this long (s), a constant
    /// acceleration of the particles the patch covered at its start (None:
    /// one impulse).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
    /// A planted stress outlier: the particles' J (and F, isotropically)
    /// scaled by this factor, so their pressure departs from their
    /// neighbours' at the next stress update. Like `dx`, its energy is not
    /// booked: the plant is an injection the detector is meant to see.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub j_scale: Option<f64>,
    /// A planted displacement (m): the particles moved by it, for example
    /// just across a node line beside empty cells (a sliver node).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dx: Option<[f64; 2]>,
}

/// An impulse as it was applied.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Planted {
    /// Index of its `[[perturb]]` entry.
    pub entry: usize,
    pub step: u64,
    /// Time at the start of the step.
    pub t: f64,
    pub region: [f64; 4],
    pub dv: [f64; 2],
    pub particles: usize,
    /// The J factor and the displacement planted with it (1 and 0 when
    /// only a velocity was).
    #[serde(default = "Planted::unscaled")]
    pub j_scale: f64,
    #[serde(default)]
    pub dx: [f64; 2],
    /// How long its velocity was spread over (s; 0: one impulse).
    #[serde(default)]
    pub duration: f64,
}

/// A plant spread over a duration: the particles its patch covered at its
/// start, by id, pushed by an equal share of `dv` per unit time.
#[derive(Clone, Debug, PartialEq)]
pub struct Sustained {
    pub entry: usize,
    pub from: f64,
    pub until: f64,
    /// The whole velocity it adds (m/s).
    pub dv: Vec2,
    /// Its particles' ids, ascending.
    pub ids: Vec<u32>,
    /// The step it last pushed, and by how much.
    pub last_step: u64,
    pub last_dv: Vec2,
}

impl Sustained {
    /// The plant of entry `entry` over `region`, adding `dv` from `from` to
    /// `until`. Its ids are its one allocation, made once at its start.
    pub fn start(
        entry: usize,
        (region, dv): ([f64; 4], Vec2),
        (from, until): (f64, f64),
        ps: &Particles,
    ) -> Self {
        let mut ids: Vec<u32> = (0..ps.len())
            .filter(|&p| covers(region, ps.x[p]))
            .map(|p| ps.id[p])
            .collect();
        ids.sort_unstable();
        Sustained {
            entry,
            from,
            until,
            dv,
            ids,
            last_step: 0,
            last_dv: Vec2::zeros(),
        }
    }

    /// The share of `dv` due in the step from `time` to `time + dt`.
    pub fn share(&self, time: f64, dt: f64) -> f64 {
        let overlap = (time + dt).min(self.until) - time.max(self.from);
        (overlap / (self.until - self.from)).clamp(0.0, 1.0)
    }

    pub fn holds(&self, id: u32) -> bool {
        self.ids.binary_search(&id).is_ok()
    }
}

impl Planted {
    fn unscaled() -> f64 {
        1.0
    }
}

impl Perturb {
    fn one_cell() -> usize {
        1
    }

    /// `dv` added to every particle in `region` after G2P of `step` (the
    /// original form of the table).
    pub fn at_step(step: u64, region: [f64; 4], dv: [f64; 2]) -> Self {
        Perturb {
            step: Some(step),
            t: None,
            region: Some(region),
            place: None,
            cells: 1,
            near: None,
            min_particles: None,
            dv: Some(dv),
            speed: None,
            direction: None,
            duration: None,
            j_scale: None,
            dx: None,
        }
    }

    /// Whether the step from `time` to `time + dt` (number `step`) applies it.
    pub fn due(&self, step: u64, time: f64, dt: f64) -> bool {
        match (self.step, self.t) {
            (Some(s), _) => s == step,
            (None, Some(t)) => time <= t && t < time + dt,
            (None, None) => false,
        }
    }

    /// Checks entry `i`: one of each pair given, values in range.
    pub fn validate(&self, i: usize, cells: [usize; 2]) -> Result<(), ConfigError> {
        let key = |k: &str| format!("perturb[{i}].{k}");
        self.validate_choices(&key)?;
        self.validate_when_where(&key, cells)?;
        self.validate_amounts(&key)
    }

    /// One of each pair (when, where, how much), and something planted.
    fn validate_choices(&self, key: &dyn Fn(&str) -> String) -> Result<(), ConfigError> {
        let one = |a: bool, b: bool, keys: &str| {
            let got = if a { "both" } else { "neither" };
            check(
                a != b,
                &key(keys),
                format!("exactly one of them is required (got {got})"),
            )
        };
        one(self.step.is_some(), self.t.is_some(), "step | t")?;
        one(
            self.region.is_some(),
            self.place.is_some(),
            "region | place",
        )?;
        if self.dv.is_some() && self.speed.is_some() {
            one(true, true, "dv | speed")?;
        }
        check(
            self.dv.is_some()
                || self.speed.is_some()
                || self.j_scale.is_some()
                || self.dx.is_some(),
            &key("dv | speed | j_scale | dx"),
            "at least one is required (got none)",
        )
    }

    /// The time, the region and the placed patch's size and count.
    fn validate_when_where(
        &self,
        key: &dyn Fn(&str) -> String,
        cells: [usize; 2],
    ) -> Result<(), ConfigError> {
        if let Some(s) = self.step {
            check(s >= 1, &key("step"), "must be >= 1")?;
        }
        if let Some(t) = self.t {
            check(
                t.is_finite() && t >= 0.0,
                &key("t"),
                format!("{t} is not a time >= 0"),
            )?;
        }
        if let Some(r) = &self.region {
            ordered_rect(r, &key("region"))?;
        }
        let largest = cells.iter().copied().min().unwrap_or(1);
        check(
            (1..=largest.min(64)).contains(&self.cells),
            &key("cells"),
            format!("{} is outside 1 ..= {}", self.cells, largest.min(64)),
        )?;
        if let Some(m) = self.min_particles {
            check(
                (1..=1_000_000_000).contains(&m),
                &key("min_particles"),
                format!("{m} is outside 1 ..= 1000000000"),
            )?;
            check(
                self.place.is_some(),
                &key("min_particles"),
                "needs place (a region is planted as given)",
            )?;
        }
        Ok(())
    }

    /// What is planted: the velocity, its duration, J's factor, the move.
    fn validate_amounts(&self, key: &dyn Fn(&str) -> String) -> Result<(), ConfigError> {
        if let Some(s) = self.j_scale {
            check(
                s.is_finite() && (0.5..=2.0).contains(&s),
                &key("j_scale"),
                format!("{s} is outside 0.5 ..= 2"),
            )?;
        }
        if let Some(dx) = &self.dx {
            check(
                dx.iter().all(|v| v.is_finite()),
                &key("dx"),
                "must be finite",
            )?;
        }
        if let Some(d) = self.duration {
            check(
                d.is_finite() && d > 0.0 && d <= 10.0,
                &key("duration"),
                format!("{d} is outside 0 < duration <= 10 s"),
            )?;
            let velocity = self.dv.is_some() || self.speed.is_some();
            check(
                velocity && self.j_scale.is_none() && self.dx.is_none(),
                &key("duration"),
                "spreads a velocity (dv or speed) only, without j_scale or dx",
            )?;
        }
        if let Some(dv) = &self.dv {
            check(
                dv.iter().all(|v| v.is_finite()),
                &key("dv"),
                "must be finite",
            )?;
        }
        if let Some(s) = self.speed {
            check(
                s.is_finite() && s >= 0.0,
                &key("speed"),
                format!("{s} is not a speed >= 0"),
            )?;
            check(
                self.direction.is_some(),
                &key("direction"),
                "is required with speed (along, against or up)",
            )?;
        }
        Ok(())
    }

    /// The region and the velocity added, resolved against the particles
    /// now; None when no patch qualifies for the placement.
    pub fn resolve(&self, frame: &Frame, ps: &Particles) -> Option<([f64; 4], Vec2)> {
        let region = match (self.region, self.place) {
            (Some(r), _) => r,
            (None, Some(place)) => {
                let least = self.min_particles.unwrap_or(0);
                place_patch(frame, ps, place, (self.cells, least), self.near)?
            }
            (None, None) => return None,
        };
        let dv = match (self.dv, self.speed, self.direction) {
            (Some(dv), _, _) => Vec2::from(dv),
            (None, Some(speed), Some(direction)) => speed * direction_in(region, ps, direction),
            (None, Some(_), None) => return None,
            (None, None, _) => Vec2::zeros(),
        };
        Some((region, dv))
    }
}

/// Whether a particle at `x` is in `region` (edges included).
pub fn covers(region: [f64; 4], x: Vec2) -> bool {
    let [x0, y0, x1, y1] = region;
    x.x >= x0 && x.x <= x1 && x.y >= y0 && x.y <= y1
}

/// The unit vector of `direction` for the particles in `region`.
fn direction_in(region: [f64; 4], ps: &Particles, direction: Direction) -> Vec2 {
    if direction == Direction::Up {
        return Vec2::new(0.0, 1.0);
    }
    let mut momentum = Vec2::zeros();
    for p in 0..ps.len() {
        if covers(region, ps.x[p]) {
            momentum += ps.mass[p] * ps.v[p];
        }
    }
    let along = if momentum.norm() > 0.0 {
        momentum / momentum.norm()
    } else {
        Vec2::new(1.0, 0.0)
    };
    match direction {
        Direction::Against => -along,
        _ => along,
    }
}

/// The `n` x `n` cell block holding at least `least` particles that
/// qualifies for `place` nearest to `near` (the box's centre by default;
/// ties to the lowest, then leftmost), as a region in metres.
fn place_patch(
    frame: &Frame,
    ps: &Particles,
    place: Placement,
    (n, least): (usize, usize),
    near: Option<[f64; 2]>,
) -> Option<[f64; 4]> {
    let [nx, ny] = frame.cells;
    let (h, o) = (frame.cell, frame.origin);
    let mut count = vec![0u32; nx * ny];
    for x in &ps.x {
        let (i, j) = ((x.x - o[0]) / h, (x.y - o[1]) / h);
        if i >= 0.0 && j >= 0.0 && (i as usize) < nx && (j as usize) < ny {
            count[i as usize + nx * j as usize] += 1;
        }
    }
    let fluid = |i: i64, j: i64| {
        i >= 0
            && j >= 0
            && (i as usize) < nx
            && (j as usize) < ny
            && count[i as usize + nx * j as usize] > 0
    };
    let target = near.unwrap_or([o[0] + 0.5 * frame.size[0], o[1] + 0.5 * frame.size[1]]);
    let mut best: Option<(f64, usize, usize)> = None;
    for j0 in 0..ny.saturating_sub(n - 1) {
        for i0 in 0..nx.saturating_sub(n - 1) {
            if !qualifies(place, (i0, j0), n, [nx, ny], &fluid) {
                continue;
            }
            let held: usize = (j0..j0 + n)
                .map(|j| {
                    (i0..i0 + n)
                        .map(|i| count[i + nx * j] as usize)
                        .sum::<usize>()
                })
                .sum();
            if held < least {
                continue;
            }
            let c = [
                o[0] + (i0 as f64 + 0.5 * n as f64) * h,
                o[1] + (j0 as f64 + 0.5 * n as f64) * h,
            ];
            let d = (c[0] - target[0]).powi(2) + (c[1] - target[1]).powi(2);
            if best.is_none_or(|b| d < b.0) {
                best = Some((d, i0, j0));
            }
        }
    }
    let (_, i0, j0) = best?;
    let (x0, y0) = (o[0] + i0 as f64 * h, o[1] + j0 as f64 * h);
    Some([x0, y0, x0 + n as f64 * h, y0 + n as f64 * h])
}

/// Whether the block at `(i0, j0)` of `n` x `n` cells qualifies for `place`.
fn qualifies(
    place: Placement,
    (i0, j0): (usize, usize),
    n: usize,
    [nx, ny]: [usize; 2],
    fluid: &impl Fn(i64, i64) -> bool,
) -> bool {
    let m = MARGIN as i64;
    let (i0, j0, n) = (i0 as i64, j0 as i64, n as i64);
    let (nx, ny) = (nx as i64, ny as i64);
    let block_fluid = (j0..j0 + n).all(|j| (i0..i0 + n).all(|i| fluid(i, j)));
    if !block_fluid {
        return false;
    }
    // Fluid in every in-box cell within the margin (`skip_top`: not above).
    let surrounded = |skip_top: bool| {
        let top = if skip_top { j0 + n - 1 } else { j0 + n - 1 + m };
        (j0 - m..=top).all(|j| {
            (i0 - m..i0 + n + m).all(|i| i < 0 || i >= nx || j < 0 || j >= ny || fluid(i, j))
        })
    };
    let off_side_walls = i0 >= m && i0 + n + m <= nx;
    match place {
        Placement::Bulk => off_side_walls && j0 >= m && j0 + n + m <= ny && surrounded(false),
        Placement::Surface => {
            let air_above = (i0..i0 + n).all(|i| !fluid(i, j0 + n));
            off_side_walls && j0 >= m && j0 + n < ny && air_above && surrounded(true)
        }
        Placement::Wall => {
            let at_wall = i0 == 0 || i0 + n == nx;
            at_wall && j0 >= m && j0 + n + m <= ny && surrounded(false)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layer(nx: usize, ny: usize, depth: usize) -> (Frame, Particles) {
        let scene = Frame {
            origin: [0.0; 2],
            size: [nx as f64 * 0.01, ny as f64 * 0.01],
            cell: 0.01,
            cells: [nx, ny],
        };
        let mut ps = Particles::default();
        for j in 0..depth {
            for i in 0..nx {
                ps.push(
                    Vec2::new((i as f64 + 0.5) * 0.01, (j as f64 + 0.5) * 0.01),
                    Vec2::zeros(),
                    1.0,
                    1.0,
                    0,
                );
            }
        }
        (scene, ps)
    }

    #[test]
    fn placed_patches_keep_their_margins() {
        let (scene, ps) = layer(20, 12, 10);
        let bulk = place_patch(&scene, &ps, Placement::Bulk, (2, 0), None).unwrap();
        // Rows 0..10 hold fluid: a bulk block ends 3 rows below the top (row 7 at most).
        assert!(
            bulk[3] <= 0.07 + 1e-12 && bulk[1] >= 0.03 - 1e-12,
            "{bulk:?}"
        );
        let surface = place_patch(&scene, &ps, Placement::Surface, (2, 0), None).unwrap();
        assert!((surface[3] - 0.10).abs() < 1e-12, "{surface:?}");
        let wall = place_patch(&scene, &ps, Placement::Wall, (2, 0), Some([0.0, 0.05])).unwrap();
        assert!(wall[0].abs() < 1e-12, "{wall:?}");
        // Too shallow a layer has no bulk.
        let (scene, ps) = layer(20, 12, 5);
        assert_eq!(
            place_patch(&scene, &ps, Placement::Bulk, (2, 0), None),
            None
        );
    }

    #[test]
    fn a_placed_patch_holds_its_least_particles() {
        // One particle per cell; the nearest bulk cell to the centre is (10, 5).
        let (scene, mut ps) = layer(20, 12, 10);
        let nearest = place_patch(&scene, &ps, Placement::Bulk, (1, 0), None).unwrap();
        assert_eq!(
            place_patch(&scene, &ps, Placement::Bulk, (1, 2), None),
            None
        );
        // A second particle in bulk cell (4, 4) makes it the only one that holds two.
        ps.push(Vec2::new(0.042, 0.043), Vec2::zeros(), 1.0, 1.0, 0);
        let held = place_patch(&scene, &ps, Placement::Bulk, (1, 2), None).unwrap();
        assert!(
            (held[0] - 0.04).abs() < 1e-12 && (held[1] - 0.04).abs() < 1e-12,
            "{held:?}"
        );
        assert_ne!(held, nearest);
        // A 2 x 2 block holds four: every block qualifies, the nearest wins.
        let block = place_patch(&scene, &ps, Placement::Bulk, (2, 4), None);
        assert_eq!(
            block,
            place_patch(&scene, &ps, Placement::Bulk, (2, 0), None)
        );
    }

    #[test]
    fn a_duration_spreads_a_velocity_only() {
        let base = Perturb::at_step(1, [0.0, 0.0, 0.1, 0.1], [0.05, 0.0]);
        let key = |p: Perturb| p.validate(0, [10, 10]).err().map(|e| e.key);
        let timed = |d: f64| Perturb {
            duration: Some(d),
            ..base.clone()
        };
        assert_eq!(key(timed(0.01)), None);
        assert_eq!(key(timed(0.0)).as_deref(), Some("perturb[0].duration"));
        let scaled = Perturb {
            j_scale: Some(1.1),
            ..timed(0.01)
        };
        assert_eq!(key(scaled).as_deref(), Some("perturb[0].duration"));
        // A least particle count sorts placed patches; a region is as given.
        let counted = Perturb {
            min_particles: Some(4),
            ..base.clone()
        };
        assert_eq!(key(counted).as_deref(), Some("perturb[0].min_particles"));
        // The share of a step: the overlap of the step with the duration.
        let s = Sustained {
            entry: 0,
            from: 1.0,
            until: 1.5,
            dv: Vec2::new(1.0, 0.0),
            ids: vec![3, 7],
            last_step: 0,
            last_dv: Vec2::zeros(),
        };
        let near = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(near(s.share(0.9, 0.2), 0.2));
        assert!(near(s.share(1.2, 0.1), 0.2));
        assert!(near(s.share(1.45, 0.1), 0.1));
        assert_eq!(s.share(1.5, 0.1), 0.0);
        assert!(s.holds(7) && !s.holds(5));
    }

    #[test]
    fn a_relative_impulse_follows_the_patch_flow() {
        let (scene, mut ps) = layer(20, 12, 10);
        for v in ps.v.iter_mut() {
            *v = Vec2::new(0.0, -2.0);
        }
        let p = |direction| Perturb {
            place: Some(Placement::Bulk),
            region: None,
            cells: 2,
            speed: Some(0.5),
            direction: Some(direction),
            dv: None,
            ..Perturb::at_step(1, [0.0; 4], [0.0; 2])
        };
        let dv = |d| p(d).resolve(&scene, &ps).unwrap().1;
        assert_eq!(dv(Direction::Along), Vec2::new(0.0, -0.5));
        assert_eq!(dv(Direction::Against), Vec2::new(0.0, 0.5));
        assert_eq!(dv(Direction::Up), Vec2::new(0.0, 0.5));
        // The step that starts at or before t and ends after it.
        let timed = Perturb {
            step: None,
            t: Some(0.25),
            ..p(Direction::Up)
        };
        assert!(!timed.due(5, 0.2, 0.05) && timed.due(6, 0.25, 0.05) && !timed.due(7, 0.3, 0.05));
    }
}
