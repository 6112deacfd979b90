//! Ray and hit files in the format of the peers' harness, little-endian: a ray file is `RAYS`,
//! u32 version 1, u64 count, then per ray 8 x f32 (origin, tmin, direction, tmax); a hit file is
//! u64 count, then per ray f32 t (+inf on a miss) and u32 triangle index (u32::MAX on a miss).
use anyhow::{Context, Result, bail};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::io::Write;
use std::path::Path;
use wavepath::{Hit, Ray};

pub const MAGIC: [u8; 4] = *b"RAYS";
pub const VERSION: u32 = 1;
const HEADER: usize = 16;

/// One ray record: ox, oy, oz, tmin, dx, dy, dz, tmax.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct RayRecord {
    pub origin: [f32; 3],
    pub tmin: f32,
    pub dir: [f32; 3],
    pub tmax: f32,
}

/// One hit record: t (+inf on a miss) and the primitive id (u32::MAX on a miss).
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct HitRecord {
    pub t: f32,
    pub prim: u32,
}

impl HitRecord {
    pub const MISS: HitRecord = HitRecord { t: f32::INFINITY, prim: u32::MAX };

    pub fn from_hit(h: Option<Hit>) -> Self {
        h.map_or(Self::MISS, |h| HitRecord { t: h.t, prim: h.prim })
    }
}

impl From<&Ray> for RayRecord {
    fn from(r: &Ray) -> Self {
        RayRecord { origin: r.origin.to_array(), tmin: r.tmin, dir: r.dir.to_array(), tmax: r.tmax }
    }
}

impl From<&RayRecord> for Ray {
    fn from(r: &RayRecord) -> Self {
        Ray { origin: Vec3::from(r.origin), dir: Vec3::from(r.dir), tmin: r.tmin, tmax: r.tmax }
    }
}

/// Parses a ray file's bytes; `path` only names the file in errors.
pub fn parse_rays(path: &Path, bytes: &[u8]) -> Result<Vec<Ray>> {
    let shown = path.display();
    if bytes.len() < HEADER {
        bail!("{shown}: truncated ray file ({} bytes, the header alone is {HEADER})", bytes.len());
    }
    if bytes[0..4] != MAGIC {
        bail!("{shown}: not a ray file (magic {:?}, expected \"RAYS\")", String::from_utf8_lossy(&bytes[0..4]));
    }
    let version = u32::from_le_bytes(bytes[4..8].try_into().expect("4 bytes"));
    if version != VERSION {
        bail!("{shown}: ray file version {version}, only version {VERSION} is supported");
    }
    let count = u64::from_le_bytes(bytes[8..16].try_into().expect("8 bytes"));
    let rec = std::mem::size_of::<RayRecord>() as u64;
    let have = (bytes.len() - HEADER) as u64;
    if count.checked_mul(rec).is_none_or(|need| need > have) {
        bail!("{shown}: header says {count} rays but the file holds data for {} ({} bytes)", have / rec, have);
    }
    let data = &bytes[HEADER..HEADER + (count * rec) as usize];
    // The data slice need not be aligned for f32: read records by value.
    Ok(data.chunks_exact(rec as usize).map(|c| Ray::from(&bytemuck::pod_read_unaligned::<RayRecord>(c))).collect())
}

pub fn read_rays(path: &Path) -> Result<Vec<Ray>> {
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    parse_rays(path, &bytes)
}

pub fn write_rays(path: &Path, rays: &[Ray]) -> Result<()> {
    let mut out = Vec::with_capacity(HEADER + 32 * rays.len());
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(rays.len() as u64).to_le_bytes());
    let recs: Vec<RayRecord> = rays.iter().map(RayRecord::from).collect();
    out.extend_from_slice(bytemuck::cast_slice(&recs));
    write_all(path, &out)
}

pub fn write_hits(path: &Path, hits: &[HitRecord]) -> Result<()> {
    let mut out = Vec::with_capacity(8 + 8 * hits.len());
    out.extend_from_slice(&(hits.len() as u64).to_le_bytes());
    out.extend_from_slice(bytemuck::cast_slice(hits));
    write_all(path, &out)
}

/// Reads a hits file (tests and tools).
pub fn read_hits(path: &Path) -> Result<Vec<HitRecord>> {
    let shown = path.display();
    let bytes = std::fs::read(path).with_context(|| format!("{shown}: cannot read"))?;
    if bytes.len() < 8 {
        bail!("{shown}: truncated hits file");
    }
    let count = u64::from_le_bytes(bytes[0..8].try_into().expect("8 bytes"));
    if count.checked_mul(8).is_none_or(|n| n != (bytes.len() - 8) as u64) {
        bail!("{shown}: header says {count} hits but the file holds {} bytes of records", bytes.len() - 8);
    }
    Ok(bytes[8..].chunks_exact(8).map(bytemuck::pod_read_unaligned).collect())
}

fn write_all(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut f = std::fs::File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
    f.write_all(bytes).with_context(|| format!("{}: cannot write", path.display()))
}
