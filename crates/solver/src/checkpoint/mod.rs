//! Versioned, checksummed binary checkpoints of the dynamic state, and the
//! 64-bit state hash. The solver only produces and consumes bytes; files are
//! the study runner's business.

mod codec;

pub use codec::{decode, encode, CodecError};

use crate::particles::{Mat2, Particles, Vec2};
use crate::Solver;

const MAGIC: &[u8; 8] = b"KICKSTAT";
pub const VERSION: u32 = 8;

#[derive(Clone, Debug, PartialEq)]
pub enum CheckpointError {
    BadMagic,
    Version(u32),
    /// A kick checkpoint of another format (`found`, `reads`: the magics).
    Format {
        found: String,
        reads: String,
    },
    /// The input ends before a field it should hold.
    Truncated,
    /// `count` bytes are left over after the last field.
    TrailingBytes {
        count: usize,
    },
    /// A string field is not valid UTF-8.
    BadUtf8,
    /// A coded field (`what`, e.g. an enum tag) holds a code this build does not know.
    UnknownCode {
        what: &'static str,
        code: u64,
    },
    Checksum {
        stored: u64,
        computed: u64,
    },
    ParticleCount {
        stored: u64,
        expected: u64,
    },
}

impl std::fmt::Display for CheckpointError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CheckpointError::BadMagic => write!(f, "not a kick checkpoint (bad magic)"),
            CheckpointError::Version(v) => {
                write!(f, "checkpoint version {v}, this build reads {VERSION}")
            }
            CheckpointError::Format { found, reads } => write!(
                f,
                "checkpoint format {found}, this build reads {reads}: it was written by \
                 another kick build (rerun the case to write checkpoints this build reads)"
            ),
            CheckpointError::Truncated => write!(f, "checkpoint is truncated"),
            CheckpointError::TrailingBytes { count } => {
                write!(
                    f,
                    "checkpoint has {count} unexpected bytes after its last field"
                )
            }
            CheckpointError::BadUtf8 => write!(f, "checkpoint holds a string that is not UTF-8"),
            CheckpointError::UnknownCode { what, code } => {
                write!(f, "checkpoint holds unknown {what} code {code}")
            }
            CheckpointError::Checksum { stored, computed } => write!(
                f,
                "checkpoint is corrupted (checksum {stored:016x}, computed {computed:016x})"
            ),
            CheckpointError::ParticleCount { stored, expected } => write!(
                f,
                "checkpoint holds {stored} particles, the scene has {expected}"
            ),
        }
    }
}

impl std::error::Error for CheckpointError {}

/// FNV-1a over 64-bit words.
#[derive(Clone, Copy)]
pub struct Hasher(u64);

impl Default for Hasher {
    fn default() -> Self {
        Hasher(0xcbf2_9ce4_8422_2325)
    }
}

impl Hasher {
    #[inline]
    pub fn word(&mut self, w: u64) {
        self.0 = (self.0 ^ w).wrapping_mul(0x0000_0100_0000_01b3);
    }

    pub fn bytes(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..chunk.len()].copy_from_slice(chunk);
            self.word(u64::from_le_bytes(w));
        }
    }

    pub fn finish(self) -> u64 {
        self.0
    }
}

pub fn state_hash(ps: &Particles) -> u64 {
    let mut h = Hasher::default();
    for p in 0..ps.len() {
        for c in ps.x[p].iter().chain(ps.v[p].iter()) {
            h.word(c.to_bits());
        }
        for c in ps.affine[p]
            .iter()
            .chain(ps.f[p].iter())
            .chain(ps.stress[p].iter())
        {
            h.word(c.to_bits());
        }
        h.word(ps.j[p].to_bits());
    }
    h.finish()
}

/// Little-endian binary writer shared by every checkpoint format (solver,
/// monitor, study runner), so f64 values round-trip bit for bit.
#[derive(Default)]
pub struct Writer(pub Vec<u8>);

impl Writer {
    pub fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn i64(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn bool(&mut self, v: bool) {
        self.u64(v as u64);
    }
    pub fn bytes(&mut self, b: &[u8]) {
        self.u64(b.len() as u64);
        self.0.extend_from_slice(b);
    }
    pub fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }
    pub fn vec2s(&mut self, vs: &[Vec2]) {
        vs.iter().flat_map(|v| v.iter()).for_each(|&c| self.f64(c));
    }
    pub fn mat2s(&mut self, ms: &[Mat2]) {
        ms.iter().flat_map(|m| m.iter()).for_each(|&c| self.f64(c));
    }
    pub fn f64s(&mut self, vs: &[f64]) {
        vs.iter().for_each(|&c| self.f64(c));
    }
    pub fn i64s(&mut self, vs: &[i64]) {
        vs.iter().for_each(|&c| self.i64(c));
    }
    pub fn u32s(&mut self, vs: &[u32]) {
        vs.iter().for_each(|&c| self.u64(c as u64));
    }
    /// Appends the FNV checksum of everything written so far.
    pub fn seal(mut self) -> Vec<u8> {
        let mut h = Hasher::default();
        h.bytes(&self.0);
        let sum = h.finish();
        self.u64(sum);
        self.0
    }
}

/// Checks `magic` and the trailing checksum of a sealed buffer and returns its body after the magic.
pub fn unseal<'a>(bytes: &'a [u8], magic: &[u8; 8]) -> Result<&'a [u8], CheckpointError> {
    if bytes.len() < 16 {
        return Err(CheckpointError::Truncated);
    }
    if &bytes[..8] != magic {
        // The same family, another version: named, so that a user knows to rerun.
        return Err(if bytes[..7] == magic[..7] {
            CheckpointError::Format {
                found: String::from_utf8_lossy(&bytes[..8]).into_owned(),
                reads: String::from_utf8_lossy(magic).into_owned(),
            }
        } else {
            CheckpointError::BadMagic
        });
    }
    let (body, tail) = bytes.split_at(bytes.len() - 8);
    let stored = u64::from_le_bytes(tail.try_into().expect("8 bytes"));
    let mut h = Hasher::default();
    h.bytes(body);
    let computed = h.finish();
    if stored != computed {
        return Err(CheckpointError::Checksum { stored, computed });
    }
    Ok(&body[8..])
}

pub struct Reader<'a>(pub &'a [u8]);

impl<'a> Reader<'a> {
    /// Takes an optional section's tag if it comes next; false, taking
    /// nothing, if it does not.
    fn take_tag(&mut self, tag: u64) -> bool {
        let tagged = self.0.get(..8).is_some_and(|b| b == tag.to_le_bytes());
        if tagged {
            self.0 = &self.0[8..];
        }
        tagged
    }

    fn take<const N: usize>(&mut self) -> Result<[u8; N], CheckpointError> {
        if self.0.len() < N {
            return Err(CheckpointError::Truncated);
        }
        let (head, rest) = self.0.split_at(N);
        self.0 = rest;
        Ok(head.try_into().expect("split at N"))
    }
    pub fn f64(&mut self) -> Result<f64, CheckpointError> {
        Ok(f64::from_le_bytes(self.take()?))
    }
    pub fn u64(&mut self) -> Result<u64, CheckpointError> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    pub fn i64(&mut self) -> Result<i64, CheckpointError> {
        Ok(i64::from_le_bytes(self.take()?))
    }
    pub fn bool(&mut self) -> Result<bool, CheckpointError> {
        Ok(self.u64()? != 0)
    }
    pub fn bytes(&mut self) -> Result<&'a [u8], CheckpointError> {
        let n = self.u64()? as usize;
        if self.0.len() < n {
            return Err(CheckpointError::Truncated);
        }
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        Ok(head)
    }
    pub fn str(&mut self) -> Result<String, CheckpointError> {
        String::from_utf8(self.bytes()?.to_vec()).map_err(|_| CheckpointError::BadUtf8)
    }
    pub fn vec2s(&mut self, out: &mut [Vec2]) -> Result<(), CheckpointError> {
        for v in out {
            *v = Vec2::new(self.f64()?, self.f64()?);
        }
        Ok(())
    }
    pub fn mat2s(&mut self, out: &mut [Mat2]) -> Result<(), CheckpointError> {
        for m in out {
            for c in m.iter_mut() {
                *c = self.f64()?;
            }
        }
        Ok(())
    }
    pub fn f64s(&mut self, out: &mut [f64]) -> Result<(), CheckpointError> {
        for v in out {
            *v = self.f64()?;
        }
        Ok(())
    }
    pub fn i64s(&mut self, out: &mut [i64]) -> Result<(), CheckpointError> {
        for v in out {
            *v = self.i64()?;
        }
        Ok(())
    }
    pub fn u32s(&mut self, out: &mut [u32]) -> Result<(), CheckpointError> {
        for v in out {
            *v = self.u64()? as u32;
        }
        Ok(())
    }
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
    /// Ok if every byte was read; `TrailingBytes` otherwise.
    pub fn finish(&self) -> Result<(), CheckpointError> {
        match self.0.len() {
            0 => Ok(()),
            count => Err(CheckpointError::TrailingBytes { count }),
        }
    }
}

pub fn save(s: &Solver) -> Vec<u8> {
    let ps = &s.particles;
    let mut w = Writer(Vec::with_capacity(64 + ps.len() * 240));
    w.0.extend_from_slice(MAGIC);
    w.u64(VERSION as u64);
    w.u64(s.n_initial as u64);
    w.u64(ps.len() as u64);
    let l = &s.losses;
    w.u64(l.escaped);
    w.u64(l.inverted);
    w.f64(l.mass_escaped);
    w.f64(l.mass_inverted);
    w.u64(l.drained);
    w.f64(l.mass_drained);
    w.u64(l.injected);
    w.f64(l.mass_injected);
    w.bool(l.t_first.is_some());
    w.f64(l.t_first.unwrap_or(0.0));
    w.u64(s.step);
    w.f64(s.time);
    w.f64(s.dt);
    w.f64(s.dt_fixed);
    w.f64(s.dissipated);
    w.vec2s(&ps.x);
    w.vec2s(&ps.v);
    w.vec2s(&ps.v_prev);
    w.vec2s(&ps.accel);
    w.mat2s(&ps.affine);
    w.mat2s(&ps.f);
    w.mat2s(&ps.stress);
    w.f64s(&ps.j);
    w.f64s(&ps.vol);
    w.f64s(&ps.mass);
    w.f64s(&ps.vol0);
    w.f64s(&ps.pressure);
    w.f64s(&ps.dev_rate);
    w.f64s(&ps.history);
    w.u32s(&ps.id);
    let material: Vec<u32> = ps.material.iter().map(|&m| m as u32).collect();
    w.u32s(&material);
    // The pressure-implicit step's cell pressure: the next solve's starting guess.
    w.u64(s.projection.pressure.len() as u64);
    w.f64s(&s.projection.pressure);
    save_fluid_cells(&mut w, s);
    save_sustained(&mut w, &s.sustained);
    w.seal()
}

/// Marks the optional section of the last step's fluid cells ("FLUIDCL1"),
/// written under `holes = "kept"`, which reads them.
const FLUID_CELLS_TAG: u64 = u64::from_le_bytes(*b"FLUIDCL1");

fn save_fluid_cells(w: &mut Writer, s: &Solver) {
    if s.cfg.method.projection.holes != crate::config::Holes::Kept {
        return;
    }
    let cells = s.projection.fluid_cells();
    w.u64(FLUID_CELLS_TAG);
    w.u64(cells.len() as u64);
    w.u32s(cells);
}

/// The last step's fluid cells, or none without the section: a restore
/// then starts as a fresh run does, whatever the solver held before.
fn load_fluid_cells(r: &mut Reader, s: &mut Solver) -> Result<(), CheckpointError> {
    let mut cells = vec![];
    if r.take_tag(FLUID_CELLS_TAG) {
        let n = r.u64()? as usize;
        // Each value is stored in 8 bytes.
        if n > r.0.len() / 8 {
            return Err(CheckpointError::Truncated);
        }
        cells.resize(n, 0u32);
        r.u32s(&mut cells)?;
    }
    s.projection
        .restore_fluid_cells(&cells)
        .map_err(|cell| CheckpointError::UnknownCode {
            what: "fluid cell",
            code: cell as u64,
        })
}

/// Marks the optional section of plants with a duration ("SUSTAIN1").
const SUSTAINED_TAG: u64 = u64::from_le_bytes(*b"SUSTAIN1");

/// Plants with a duration still pushing, after everything else, behind
/// their tag (none: nothing written, so a checkpoint without one is as
/// before and any other trailing bytes stay an error).
fn save_sustained(w: &mut Writer, sustained: &[crate::Sustained]) {
    if sustained.is_empty() {
        return;
    }
    w.u64(SUSTAINED_TAG);
    w.u64(sustained.len() as u64);
    for s in sustained {
        w.u64(s.entry as u64);
        w.f64s(&[s.from, s.until, s.dv.x, s.dv.y]);
        w.u64(s.last_step);
        w.f64s(&[s.last_dv.x, s.last_dv.y]);
        w.u64(s.ids.len() as u64);
        w.u32s(&s.ids);
    }
}

fn load_sustained(r: &mut Reader, out: &mut Vec<crate::Sustained>) -> Result<(), CheckpointError> {
    out.clear();
    if !r.take_tag(SUSTAINED_TAG) {
        return Ok(());
    }
    for k in 0..r.u64()? {
        let entry = r.u64()? as usize;
        let mut f = [0.0; 4];
        r.f64s(&mut f)?;
        let last_step = r.u64()?;
        let mut last = [0.0; 2];
        r.f64s(&mut last)?;
        let n = r.u64()? as usize;
        if n > r.0.len() / 8 {
            return Err(CheckpointError::Truncated);
        }
        let mut ids = vec![0u32; n];
        r.u32s(&mut ids)?;
        let span_ok = f[..2].iter().all(|t| t.is_finite()) && f[0] < f[1];
        let ids_ok = ids.windows(2).all(|w| w[0] < w[1]);
        if !(span_ok && ids_ok) {
            return Err(CheckpointError::UnknownCode {
                what: "sustained plant (span or particle order)",
                code: k,
            });
        }
        out.push(crate::Sustained {
            entry,
            from: f[0],
            until: f[1],
            dv: Vec2::new(f[2], f[3]),
            ids,
            last_step,
            last_dv: Vec2::new(last[0], last[1]),
        });
    }
    Ok(())
}

/// What `save` writes before the dynamic fields.
struct Header {
    n_initial: u64,
    n: u64,
    losses: crate::Losses,
    step: u64,
    time: f64,
}

fn read_header(r: &mut Reader) -> Result<Header, CheckpointError> {
    let version = r.u64().map(|w| w as u32)?;
    if version != VERSION {
        return Err(CheckpointError::Version(version));
    }
    let n_initial = r.u64()?;
    let n = r.u64()?;
    let escaped = r.u64()?;
    let inverted = r.u64()?;
    let mass_escaped = r.f64()?;
    let mass_inverted = r.f64()?;
    let drained = r.u64()?;
    let mass_drained = r.f64()?;
    let injected = r.u64()?;
    let mass_injected = r.f64()?;
    let has_first = r.bool()?;
    let t_first = r.f64()?;
    let losses = crate::Losses {
        escaped,
        inverted,
        mass_escaped,
        mass_inverted,
        t_first: has_first.then_some(t_first),
        drained,
        mass_drained,
        injected,
        mass_injected,
    };
    let step = r.u64()?;
    let time = r.f64()?;
    Ok(Header {
        n_initial,
        n,
        losses,
        step,
        time,
    })
}

/// A checkpoint's step and time, read from its header without restoring it
/// (to choose which of a case's checkpoints a replay starts from).
pub fn clock(bytes: &[u8]) -> Result<(u64, f64), CheckpointError> {
    let h = read_header(&mut Reader(unseal(bytes, MAGIC)?))?;
    Ok((h.step, h.time))
}

pub fn load(s: &mut Solver, bytes: &[u8]) -> Result<(), CheckpointError> {
    let body = unseal(bytes, MAGIC)?;
    let mut r = Reader(body);
    let Header {
        n_initial,
        n,
        losses,
        step,
        time,
    } = read_header(&mut r)?;
    let expected = s.n_initial as u64;
    if n_initial != expected {
        return Err(CheckpointError::ParticleCount {
            stored: n_initial,
            expected,
        });
    }
    let (escaped, inverted, drained) = (losses.escaped, losses.inverted, losses.drained);
    let accounted = [escaped, inverted, drained]
        .into_iter()
        .try_fold(n, |sum, k| sum.checked_add(k));
    if accounted != n_initial.checked_add(losses.injected) {
        return Err(CheckpointError::ParticleCount {
            stored: n
                .saturating_add(escaped)
                .saturating_add(inverted)
                .saturating_add(drained),
            expected,
        });
    }
    s.losses = losses;
    s.culled.clear();
    s.step = step;
    s.time = time;
    s.dt = r.f64()?;
    s.dt_fixed = r.f64()?;
    s.dissipated = r.f64()?;
    let ps = &mut s.particles;
    ps.resize(n as usize);
    s.stencils.resize(n as usize, Default::default());
    r.vec2s(&mut ps.x)?;
    r.vec2s(&mut ps.v)?;
    r.vec2s(&mut ps.v_prev)?;
    r.vec2s(&mut ps.accel)?;
    r.mat2s(&mut ps.affine)?;
    r.mat2s(&mut ps.f)?;
    r.mat2s(&mut ps.stress)?;
    r.f64s(&mut ps.j)?;
    r.f64s(&mut ps.vol)?;
    r.f64s(&mut ps.mass)?;
    r.f64s(&mut ps.vol0)?;
    r.f64s(&mut ps.pressure)?;
    r.f64s(&mut ps.dev_rate)?;
    r.f64s(&mut ps.history)?;
    r.u32s(&mut ps.id)?;
    let mut material = vec![0u32; n as usize];
    r.u32s(&mut material)?;
    let n_materials = s.cfg.scene.materials.len().max(1);
    for (m, code) in ps.material.iter_mut().zip(material) {
        if code as usize >= n_materials {
            return Err(CheckpointError::UnknownCode {
                what: "material",
                code: code as u64,
            });
        }
        *m = code as u16;
    }
    let cells = r.u64()?;
    if cells != s.projection.pressure.len() as u64 {
        return Err(CheckpointError::UnknownCode {
            what: "cell pressure count",
            code: cells,
        });
    }
    r.f64s(&mut s.projection.pressure)?;
    load_fluid_cells(&mut r, s)?;
    load_sustained(&mut r, &mut s.sustained)?;
    r.finish()
}
