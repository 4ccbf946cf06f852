//! Particle snapshots: what the maps and animations need of a state
//! (positions, velocity, pressure, acceleration, id), written as VTK XML
//! (`.vtu`, binary appended) for ParaView and read back by the report; each
//! particle folder gets a `.pvd` time collection (`write_collections`), so
//! ParaView opens a run as one time series.

use crate::output::files::write_atomic;
use solver::{StateView, Vec2};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The extension of the particle files.
pub const EXTENSION: &str = "vtu";

/// `{prefix}_{step:09}.vtu` (`particles_000001234.vtu`, `fluid_...`).
pub fn file_name(prefix: &str, step: u64) -> String {
    format!("{prefix}_{step:09}.{EXTENSION}")
}

/// Writes `snap` as `dir/{prefix}_{step:09}.vtu`.
pub fn write_file(dir: &Path, prefix: &str, snap: &Snapshot) -> std::io::Result<()> {
    write_atomic(&dir.join(file_name(prefix, snap.step)), &snap.vtu())
}

/// Reads a particle file: `.vtu`, or a legacy `.vtk` of an older case folder.
pub fn read_file(path: &Path) -> Result<Snapshot, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let snap = if path.extension().is_some_and(|e| e == "vtk") {
        Snapshot::from_vtk(&String::from_utf8_lossy(&bytes))
    } else {
        Snapshot::from_vtu(&bytes)
    };
    snap.map_err(|e| format!("{}: {e}", path.display()))
}

/// The particle files of a folder (`.vtu`, else legacy `.vtk`), sorted by
/// name (= by prefix, then step).
pub fn particle_files(dir: &Path) -> Vec<PathBuf> {
    let with = |ext: &str| -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
            .map(|r| {
                r.filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.extension().is_some_and(|x| x == ext))
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    };
    let files = with(EXTENSION);
    if files.is_empty() {
        with("vtk")
    } else {
        files
    }
}

/// Writes `NAME.pvd` into folder `dir` (named NAME) and into each of its
/// subfolders that hold particle files (`event_K/event_K.pvd`): a ParaView
/// collection of every `.vtu` there with its time; files of different
/// prefixes (a mixture's `fluid_` and `solid_`) are parts of one time step.
/// Nothing is written for a folder without `.vtu` files.
pub fn write_collections(dir: &Path) -> std::io::Result<()> {
    let mut folders = vec![dir.to_path_buf()];
    if let Ok(entries) = std::fs::read_dir(dir) {
        let mut subs: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_dir())
            .collect();
        subs.sort();
        folders.extend(subs);
    }
    for folder in folders {
        let files: Vec<PathBuf> = particle_files(&folder)
            .into_iter()
            .filter(|p| p.extension().is_some_and(|x| x == EXTENSION))
            .collect();
        let Some(name) = folder.file_name().map(|n| n.to_string_lossy().into_owned()) else {
            continue;
        };
        if files.is_empty() {
            continue;
        }
        let mut parts: Vec<String> = vec![];
        let mut rows = vec![];
        for f in &files {
            let file = f
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let prefix = file.rsplit_once('_').map_or("", |(p, _)| p).to_string();
            let part = match parts.iter().position(|p| *p == prefix) {
                Some(k) => k,
                None => {
                    parts.push(prefix);
                    parts.len() - 1
                }
            };
            let t = vtu_time(f).map_err(std::io::Error::other)?;
            rows.push((t, part, file));
        }
        rows.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut xml = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n",
        );
        for (t, part, file) in rows {
            xml.push_str(&format!(
                "<DataSet timestep=\"{t}\" group=\"\" part=\"{part}\" file=\"{}\"/>\n",
                crate::output::escape(&file)
            ));
        }
        xml.push_str("</Collection>\n</VTKFile>\n");
        write_atomic(&folder.join(format!("{name}.pvd")), xml.as_bytes())?;
    }
    Ok(())
}

/// The time of a `.vtu` file, from its header alone.
fn vtu_time(path: &Path) -> Result<f64, String> {
    use std::io::Read;
    let mut head = vec![0u8; 4096];
    let mut f = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut got = 0;
    loop {
        let k = f
            .read(&mut head[got..])
            .map_err(|e| format!("{}: {e}", path.display()))?;
        got += k;
        if k == 0 || got == head.len() {
            break;
        }
    }
    let text = String::from_utf8_lossy(&head[..got]);
    field_value(&text, "TimeValue").map_err(|e| format!("{}: {e}", path.display()))
}

/// Uncompressed bytes per zlib block (VTK's default).
const ZLIB_BLOCK: usize = 1 << 15;

/// One array as vtkZLibDataCompressor lays it out with UInt64 headers:
/// [blocks, block size, size of a partial last block (0 if full), each
/// block's compressed size], then the compressed blocks.
fn zlib_blocks(bytes: &[u8]) -> Vec<u8> {
    use flate2::{write::ZlibEncoder, Compression};
    use std::io::Write;
    let blocks: Vec<Vec<u8>> = bytes
        .chunks(ZLIB_BLOCK)
        .map(|chunk| {
            let mut z =
                ZlibEncoder::new(Vec::with_capacity(chunk.len() / 2), Compression::default());
            z.write_all(chunk).expect("writing to a Vec");
            z.finish().expect("writing to a Vec")
        })
        .collect();
    let mut out = vec![];
    for h in [blocks.len(), ZLIB_BLOCK, bytes.len() % ZLIB_BLOCK]
        .into_iter()
        .chain(blocks.iter().map(Vec::len))
    {
        out.extend_from_slice(&(h as u64).to_le_bytes());
    }
    for b in &blocks {
        out.extend_from_slice(b);
    }
    out
}

/// Reads one array at `offset` of the appended data: zlib blocks when
/// `compressed`, else a UInt64 byte count and the raw bytes.
fn appended_array(data: &[u8], offset: usize, compressed: bool) -> Result<Vec<u8>, String> {
    let word = |at: usize| -> Result<usize, String> {
        let b = data.get(at..at + 8).ok_or("array header past the data")?;
        Ok(u64::from_le_bytes(b.try_into().expect("8 bytes")) as usize)
    };
    if !compressed {
        let len = word(offset)?;
        return data
            .get(offset + 8..offset + 8 + len)
            .map(<[u8]>::to_vec)
            .ok_or_else(|| "truncated data".into());
    }
    use std::io::Read;
    let blocks = word(offset)?;
    if blocks > data.len() {
        return Err("bad block count".into());
    }
    let mut at = offset + 8 * (3 + blocks);
    let mut out = vec![];
    for k in 0..blocks {
        let size = word(offset + 8 * (3 + k))?;
        let block = data.get(at..at + size).ok_or("truncated data")?;
        flate2::read::ZlibDecoder::new(block)
            .read_to_end(&mut out)
            .map_err(|e| format!("bad zlib block: {e}"))?;
        at += size;
    }
    Ok(out)
}

/// A `.vtu`'s XML header (up to and including the `_` that opens the
/// appended data) and the appended data after it.
fn vtu_parts(bytes: &[u8]) -> Result<(&str, &[u8]), String> {
    const OPEN: &[u8] = b"<AppendedData encoding=\"raw\">";
    let at = bytes
        .windows(OPEN.len())
        .position(|w| w == OPEN)
        .ok_or("no raw AppendedData")?;
    let underscore = at
        + OPEN.len()
        + bytes[at + OPEN.len()..]
            .iter()
            .position(|&b| b == b'_')
            .ok_or("AppendedData lacks its _")?;
    let header = std::str::from_utf8(&bytes[..underscore]).map_err(|_| "header not UTF-8")?;
    Ok((header, &bytes[underscore + 1..]))
}

/// The value of attribute `key="..."` in a piece of XML.
fn attribute(xml: &str, key: &str) -> Option<String> {
    let pattern = format!(" {key}=\"");
    let start = xml.find(&pattern)? + pattern.len();
    let len = xml[start..].find('"')?;
    Some(xml[start..start + len].to_string())
}

/// The inline ascii value of the field data array `name`.
fn field_value<T: std::str::FromStr>(header: &str, name: &str) -> Result<T, String> {
    let tag = format!("Name=\"{name}\"");
    let at = header.find(&tag).ok_or(format!("no {name}"))?;
    let rest = &header[at..];
    let start = rest.find('>').ok_or(format!("bad {name}"))? + 1;
    let end = rest.find("</DataArray>").ok_or(format!("bad {name}"))?;
    rest.get(start..end)
        .and_then(|v| v.trim().parse().ok())
        .ok_or(format!("bad {name}"))
}

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

    /// VTK XML UnstructuredGrid (`.vtu`, ParaView's own format): the points
    /// (Float32) and one vertex cell per particle, the point data as Float32
    /// (pressure, accel, J, xi when captured, velocity) and UInt32 (id), all
    /// as raw binary appended data, little-endian, each array zlib-compressed
    /// as VTK's vtkZLibDataCompressor writes it (UInt64 headers). The step
    /// and time are inline field data (`Step`, `TimeValue`), which
    /// `write_collections` reads for the `.pvd`.
    pub fn vtu(&self) -> Vec<u8> {
        let arrays = self.vtu_arrays();
        let blocks: Vec<Vec<u8>> = arrays.iter().map(|a| zlib_blocks(&a.3)).collect();
        let mut offset = 0usize;
        let mut tags = BTreeMap::new();
        for ((name, ty, comps, _), bytes) in arrays.iter().zip(&blocks) {
            tags.insert(
                *name,
                format!(
                    "<DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"appended\" offset=\"{offset}\"/>"
                ),
            );
            offset += bytes.len();
        }
        let mut out = self.vtu_header(&tags).into_bytes();
        out.reserve(offset + 64);
        for bytes in &blocks {
            out.extend_from_slice(bytes);
        }
        out.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
        out
    }

    /// The arrays of the appended block, in its order: (name, VTK type,
    /// components, little-endian bytes before compression).
    fn vtu_arrays(&self) -> Vec<(&'static str, &'static str, usize, Vec<u8>)> {
        let n = self.x.len();
        let f32s = |v: &mut Vec<u8>, it: &mut dyn Iterator<Item = f64>| {
            for x in it {
                v.extend_from_slice(&(x as f32).to_le_bytes());
            }
        };
        let mut arrays: Vec<(&str, &str, usize, Vec<u8>)> = vec![];
        let mut points = Vec::with_capacity(12 * n);
        f32s(
            &mut points,
            &mut self.x.iter().flat_map(|x| [x.x, x.y, 0.0]),
        );
        arrays.push(("Points", "Float32", 3, points));
        // One vertex cell per particle (VTK_VERTEX): every reader draws them.
        let (mut connectivity, mut offsets) =
            (Vec::with_capacity(4 * n), Vec::with_capacity(4 * n));
        for p in 0..n as i32 {
            connectivity.extend_from_slice(&p.to_le_bytes());
            offsets.extend_from_slice(&(p + 1).to_le_bytes());
        }
        arrays.push(("connectivity", "Int32", 1, connectivity));
        arrays.push(("offsets", "Int32", 1, offsets));
        arrays.push(("types", "UInt8", 1, vec![1u8; n]));
        let scalar = |v: &[f64]| {
            let mut b = Vec::with_capacity(4 * v.len());
            f32s(&mut b, &mut v.iter().copied());
            b
        };
        arrays.push(("pressure", "Float32", 1, scalar(&self.pressure)));
        arrays.push(("accel", "Float32", 1, scalar(&self.accel)));
        arrays.push(("J", "Float32", 1, scalar(&self.j)));
        if !self.history.is_empty() {
            arrays.push(("xi", "Float32", 1, scalar(&self.history)));
        }
        let mut id = Vec::with_capacity(4 * n);
        for i in &self.id {
            id.extend_from_slice(&i.to_le_bytes());
        }
        arrays.push(("id", "UInt32", 1, id));
        let mut velocity = Vec::with_capacity(12 * n);
        f32s(
            &mut velocity,
            &mut self.v.iter().flat_map(|u| [u.x, u.y, 0.0]),
        );
        arrays.push(("velocity", "Float32", 3, velocity));
        arrays
    }

    /// The XML up to the appended data's `_`, with each array's tag (`tags`,
    /// by name) where it belongs.
    fn vtu_header(&self, tags: &BTreeMap<&str, String>) -> String {
        use std::fmt::Write;
        let n = self.x.len();
        let mut h = String::with_capacity(2048);
        let _ = write!(
            h,
            "<?xml version=\"1.0\"?>\n\
             <VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n\
             <UnstructuredGrid>\n\
             <FieldData>\n\
             <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>\n\
             <DataArray type=\"Int64\" Name=\"Step\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>\n\
             </FieldData>\n\
             <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">\n\
             <PointData Scalars=\"pressure\" Vectors=\"velocity\">\n",
            self.t, self.step
        );
        for name in ["pressure", "accel", "J", "xi", "id", "velocity"] {
            if let Some(tag) = tags.get(name) {
                let _ = writeln!(h, "{tag}");
            }
        }
        let tag = |name: &str| tags.get(name).map_or("", String::as_str);
        let _ = write!(
            h,
            "</PointData>\n<Points>\n{}\n</Points>\n<Cells>\n",
            tag("Points")
        );
        for name in ["connectivity", "offsets", "types"] {
            let _ = writeln!(h, "{}", tag(name));
        }
        h.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_");
        h
    }

    /// Reads what `vtu` wrote (Float32 fields come back as their f64 value).
    pub fn from_vtu(bytes: &[u8]) -> Result<Snapshot, String> {
        let (header, data) = vtu_parts(bytes)?;
        if !header.contains("byte_order=\"LittleEndian\"")
            || !header.contains("header_type=\"UInt64\"")
        {
            return Err("not a little-endian UInt64-header .vtu".into());
        }
        let mut snap = Snapshot {
            t: field_value(header, "TimeValue")?,
            step: field_value(header, "Step")?,
            ..Default::default()
        };
        let n: usize = attribute(header, "NumberOfPoints")
            .and_then(|v| v.parse().ok())
            .ok_or("no NumberOfPoints")?;
        let compressed = header.contains("compressor=\"vtkZLibDataCompressor\"");
        let mut arrays: BTreeMap<String, (String, usize, Vec<u8>)> = BTreeMap::new();
        for tag in header.split("<DataArray").skip(1) {
            let tag = &tag[..tag.find('>').unwrap_or(tag.len())];
            if attribute(tag, "format").as_deref() != Some("appended") {
                continue;
            }
            let get = |k: &str| attribute(tag, k).ok_or(format!("DataArray lacks {k}"));
            let name = get("Name")?;
            let offset: usize = get("offset")?.parse().map_err(|_| "bad offset")?;
            let comps: usize = get("NumberOfComponents")?
                .parse()
                .map_err(|_| "bad NumberOfComponents")?;
            let block =
                appended_array(data, offset, compressed).map_err(|e| format!("{name}: {e}"))?;
            arrays.insert(name, (get("type")?, comps, block));
        }
        let values = |name: &str, comps: usize| -> Result<Option<Vec<f64>>, String> {
            let Some((ty, c, block)) = arrays.get(name) else {
                return Ok(None);
            };
            let width = match ty.as_str() {
                "Float32" | "UInt32" => 4,
                _ => return Err(format!("{name}: unexpected type {ty}")),
            };
            if *c != comps || block.len() != width * comps * n {
                return Err(format!("{name}: {} bytes for {n} points", block.len()));
            }
            Ok(Some(
                block
                    .chunks_exact(4)
                    .map(|b| {
                        let b: [u8; 4] = b.try_into().expect("4 bytes");
                        match ty.as_str() {
                            "Float32" => f32::from_le_bytes(b) as f64,
                            _ => u32::from_le_bytes(b) as f64,
                        }
                    })
                    .collect(),
            ))
        };
        fn pairs(v: Vec<f64>) -> Vec<Vec2> {
            v.chunks_exact(3).map(|c| Vec2::new(c[0], c[1])).collect()
        }
        snap.x = pairs(values("Points", 3)?.ok_or("no points")?);
        snap.v = values("velocity", 3)?
            .map(pairs)
            .unwrap_or_else(|| vec![Vec2::zeros(); n]);
        snap.pressure = values("pressure", 1)?.ok_or("no pressure")?;
        snap.accel = values("accel", 1)?.unwrap_or_else(|| vec![0.0; n]);
        snap.j = values("J", 1)?.unwrap_or_else(|| vec![1.0; n]);
        snap.history = values("xi", 1)?.unwrap_or_default();
        snap.id = values("id", 1)?
            .map(|v| v.into_iter().map(|i| i as u32).collect())
            .unwrap_or_default();
        Ok(snap)
    }

    /// Reads a legacy ASCII VTK file (`.vtk`) as kick wrote them before
    /// the `.vtu` files, so older case folders still get their report.
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

    /// The snapshot as Float32 keeps it: positions, velocity and the fields
    /// rounded to f32; step, time and id exact.
    fn as_f32(s: &Snapshot) -> Snapshot {
        let r = |v: f64| v as f32 as f64;
        let rv = |u: &Vec2| Vec2::new(r(u.x), r(u.y));
        Snapshot {
            x: s.x.iter().map(rv).collect(),
            v: s.v.iter().map(rv).collect(),
            pressure: s.pressure.iter().copied().map(r).collect(),
            accel: s.accel.iter().copied().map(r).collect(),
            j: s.j.iter().copied().map(r).collect(),
            history: s.history.iter().copied().map(r).collect(),
            ..s.clone()
        }
    }

    /// Every field round-trips through the `.vtu` (to f32 where Float32);
    /// xi is written only for a softening solid, and a file without it
    /// reads back with none; the step and time are exact.
    #[test]
    fn vtu_round_trips_to_f32_and_writes_xi_only_when_captured() {
        for history in [vec![0.0, 1.5e-3], vec![]] {
            let mut s = snapshot(history.clone());
            s.t = 0.1 + 0.2;
            s.x[0].x = 0.123_456_789_012_345;
            let bytes = s.vtu();
            let head = String::from_utf8_lossy(&bytes[..bytes.len().min(3000)]).into_owned();
            assert_eq!(head.contains("Name=\"xi\""), !history.is_empty());
            assert!(head.contains("header_type=\"UInt64\""), "{head}");
            assert!(
                head.contains("compressor=\"vtkZLibDataCompressor\""),
                "{head}"
            );
            let back = Snapshot::from_vtu(&bytes).unwrap();
            assert_eq!(back, as_f32(&s));
            assert_eq!(back.t, 0.1 + 0.2);
            assert_ne!(back.x[0].x, s.x[0].x, "positions are Float32");
        }
        // Arrays of several zlib blocks (10^4 particles: 120 kB of points).
        let n = 10_000;
        let big = Snapshot {
            step: 1,
            t: 0.5,
            x: (0..n).map(|k| Vec2::new(k as f64 * 1e-4, 0.3)).collect(),
            v: vec![Vec2::new(0.5, -0.25); n],
            pressure: (0..n).map(|k| k as f64).collect(),
            accel: vec![9.81; n],
            j: vec![1.0; n],
            history: vec![],
            id: (0..n as u32).collect(),
        };
        let bytes = big.vtu();
        assert!(bytes.len() < 30 * n, "compressed: {} bytes", bytes.len());
        assert_eq!(Snapshot::from_vtu(&bytes).unwrap(), as_f32(&big));
        // No particles: an empty piece reads back empty.
        let empty = Snapshot {
            step: 3,
            t: 1.0,
            ..Default::default()
        };
        assert_eq!(Snapshot::from_vtu(&empty.vtu()).unwrap(), empty);
        // A truncated file is an error, not a panic.
        let bytes = snapshot(vec![]).vtu();
        assert!(Snapshot::from_vtu(&bytes[..bytes.len() - 60]).is_err());
    }

    /// A legacy ASCII file of an older case folder still reads.
    #[test]
    fn legacy_vtk_still_reads() {
        let text =
            "# vtk DataFile Version 3.0\nkick particles step 7 t 0.25\nASCII\nDATASET POLYDATA\n\
                    POINTS 2 double\n0.1 0.2 0\n0.3 0.4 0\nVERTICES 2 4\n1 0\n1 1\nPOINT_DATA 2\n\
                    SCALARS pressure double 1\nLOOKUP_TABLE default\n10\n-2.5\n\
                    SCALARS accel double 1\nLOOKUP_TABLE default\n0\n9.81\n\
                    SCALARS J double 1\nLOOKUP_TABLE default\n1\n0.99\n\
                    SCALARS id double 1\nLOOKUP_TABLE default\n4\n9\n\
                    VECTORS velocity double\n1 -1 0\n0.5 0 0\n";
        assert_eq!(Snapshot::from_vtk(text).unwrap(), snapshot(vec![]));
    }

    /// Each folder's `.pvd` lists every `.vtu` with its time, a mixture's
    /// phases as parts of one step; an event subfolder gets its own.
    #[test]
    fn collections_list_every_file_with_its_time() {
        let dir = std::env::temp_dir().join(format!("kick-pvd-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let particles = dir.join("particles");
        let event = particles.join("event_2");
        for (step, t) in [(0u64, 0.0), (40, 0.05), (400, 0.5)] {
            let s = Snapshot {
                step,
                t,
                ..snapshot(vec![])
            };
            write_file(&particles, "fluid", &s).unwrap();
            write_file(&particles, "solid", &s).unwrap();
            write_file(&event, "particles", &s).unwrap();
        }
        write_collections(&particles).unwrap();
        let pvd = std::fs::read_to_string(particles.join("particles.pvd")).unwrap();
        let rows: Vec<&str> = pvd.lines().filter(|l| l.starts_with("<DataSet")).collect();
        assert_eq!(rows.len(), 6, "{pvd}");
        assert_eq!(
            rows[0],
            "<DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"fluid_000000000.vtu\"/>"
        );
        assert_eq!(
            rows[5],
            "<DataSet timestep=\"0.5\" group=\"\" part=\"1\" file=\"solid_000000400.vtu\"/>"
        );
        let pvd = std::fs::read_to_string(event.join("event_2.pvd")).unwrap();
        assert!(pvd
            .contains("timestep=\"0.05\" group=\"\" part=\"0\" file=\"particles_000000040.vtu\""));
        assert_eq!(particle_files(&event).len(), 3);
        let back = read_file(&event.join(file_name("particles", 400))).unwrap();
        assert_eq!((back.step, back.t), (400, 0.5));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
