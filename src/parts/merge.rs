//! Combining parts into the render a single process would have made.

use super::file::{self, Part, PartMeta};
use super::spec::Split;
use super::stats::PartStats;
use anyhow::{Result, bail};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use wavepath::Accumulator;

/// A merged render: the sums of every pixel and the parts' headers (in part order).
pub struct Merged {
    pub acc: Accumulator,
    pub parts: Vec<PartMeta>,
}

/// Reads and merges part files. Refuses, with one line naming the part, a file that is not
/// a complete part, parts of different scenes, settings, splits or counts, a part given
/// twice, and a missing part. Every header is checked before any pixels are read; then the
/// parts are read and added one at a time, in part order, so memory stays at two images
/// and the summation order never depends on the order the files are given in.
pub fn merge_files(paths: &[impl AsRef<Path>]) -> Result<Merged> {
    if paths.is_empty() {
        bail!("merge: no part files given");
    }
    let metas = paths
        .iter()
        .map(|p| Ok((p.as_ref().to_path_buf(), file::read_meta(p.as_ref())?)))
        .collect::<Result<Vec<_>>>()?;
    let order = check(&metas)?;
    let (w, h) = (metas[0].1.width, metas[0].1.height);
    let mut acc = Accumulator::new(w, h);
    let mut parts = Vec::with_capacity(order.len());
    for k in order {
        let (path, meta) = &metas[k];
        let part = file::read(path)?;
        if &part.meta != meta {
            bail!("{}: changed while merging", path.display());
        }
        add(&mut acc, &part)?;
        parts.push(part.meta);
    }
    Ok(Merged { acc, parts })
}

/// Checks that the parts belong together; returns their positions in part order.
fn check(parts: &[(PathBuf, PartMeta)]) -> Result<Vec<usize>> {
    let (fpath, f) = &parts[0];
    let fname = fpath.display();
    let n = f.part.count as usize;
    let mut slots: Vec<Option<usize>> = vec![None; n];
    for (k, (path, m)) in parts.iter().enumerate() {
        let name = path.display();
        let differs = |what: &str, a: &dyn std::fmt::Display, b: &dyn std::fmt::Display| -> anyhow::Error {
            anyhow::anyhow!("{name}: {what} differs from {fname} ({a} vs {b})")
        };
        if m.scene_hash != f.scene_hash {
            return Err(differs(
                "scene",
                &format!("{} {}", m.scene, m.scene_hash),
                &format!("{} {}", f.scene, f.scene_hash),
            ));
        }
        if m.part.count != f.part.count {
            return Err(differs("number of parts", &m.part.count, &f.part.count));
        }
        if m.part.split != f.part.split {
            return Err(differs("split", &m.part.split.name(), &f.part.split.name()));
        }
        if m.settings != f.settings || (m.width, m.height, m.spp) != (f.width, f.height, f.spp) {
            let (a, b) = setting_difference(&m.settings, &f.settings);
            return Err(differs("render settings", &a, &b));
        }
        let i = m.part.index as usize;
        if let Some(other) = slots[i] {
            bail!("{name}: part {} given twice (also {})", m.part.label(), parts[other].0.display());
        }
        slots[i] = Some(k);
    }
    if let Some(i) = slots.iter().position(|s| s.is_none()) {
        bail!("merge: part {i}/{n} is missing ({} of {n} parts given)", slots.iter().flatten().count());
    }
    Ok(slots.into_iter().flatten().collect())
}

/// Adds one part's sums. For tiles every pixel gets one non-zero term and 0 + x == x
/// exactly, so the merge reproduces the single-process sums bit for bit.
fn add(acc: &mut Accumulator, p: &Part) -> Result<()> {
    if p.meta.part.split == Split::Tiles {
        let h = p.acc.height;
        for (y, row) in p.acc.pixels.chunks(p.acc.width).enumerate() {
            if !p.meta.part.owns_row(y, h) && row.iter().any(|px| px.taken != 0) {
                bail!("{}: has samples in row {y}, which belongs to another part", p.path.display());
            }
        }
    }
    for (a, b) in acc.pixels.iter_mut().zip(&p.acc.pixels) {
        a.merge(b);
    }
    Ok(())
}

/// The settings that differ between two settings keys (`Debug` of [`wavepath::Settings`]),
/// so the refusal says `seed: 3` vs `seed: 0` rather than two whole structs.
fn setting_difference(a: &str, b: &str) -> (String, String) {
    let fields = |s: &str| -> Vec<String> {
        let inner = s.trim_start_matches("Settings {").trim_end_matches('}');
        inner.split(", ").map(|f| f.trim().to_string()).collect()
    };
    let (fa, fb) = (fields(a), fields(b));
    if fa.len() != fb.len() {
        return (a.to_string(), b.to_string());
    }
    let (da, db): (Vec<_>, Vec<_>) = fa.into_iter().zip(fb).filter(|(x, y)| x != y).unzip();
    (da.join(", "), db.join(", "))
}

impl Merged {
    /// Statistics of the whole render: rays and time per stage summed over the parts,
    /// `render_s` and `wall_s` of the slowest part (the wall time when parts run at once).
    pub fn stats_json(&self) -> Value {
        let m = &self.parts[0];
        let mut total = PartStats::default();
        let (mut slowest_render, mut slowest_wall, mut build) = (0.0f64, 0.0f64, 0.0f64);
        for p in &self.parts {
            let s = &p.stats;
            total.camera_rays += s.camera_rays;
            total.extension_rays += s.extension_rays;
            total.shadow_rays += s.shadow_rays;
            total.light_rays += s.light_rays;
            total.prim_tests += s.prim_tests;
            total.nodes += s.nodes;
            total.stages.add(&s.stages);
            total.render_s += s.render_s;
            total.wall_s += s.wall_s;
            slowest_render = slowest_render.max(s.render_s);
            slowest_wall = slowest_wall.max(s.wall_s);
            build = build.max(s.build_s);
        }
        let taken = self.acc.samples_taken();
        let pixels = taken.len().max(1) as f64;
        let rays = total.rays();
        let traced = (rays).max(1) as f64;
        json!({
            "scene": m.scene,
            "scene_hash": m.scene_hash,
            "width": m.width,
            "height": m.height,
            "spp": m.spp,
            "split": m.part.split.name(),
            "parts": self.parts.len(),
            "rays": {
                "camera": total.camera_rays,
                "extension": total.extension_rays,
                "shadow": total.shadow_rays,
                "light": total.light_rays,
                "total": rays,
            },
            "render_s": slowest_render,
            "wall_s": slowest_wall,
            "render_s_sum": total.render_s,
            "wall_s_sum": total.wall_s,
            "bvh": { "build_s": build },
            "mrays_per_s": if slowest_render > 0.0 { rays as f64 / slowest_render / 1e6 } else { 0.0 },
            "intersection_tests_per_ray": total.prim_tests as f64 / traced,
            "nodes_visited_per_ray": total.nodes as f64 / traced,
            "stages": total.stages,
            "samples_per_pixel": {
                "mean": taken.iter().map(|&t| t as f64).sum::<f64>() / pixels,
                "min": taken.iter().copied().min().unwrap_or(0),
                "max": taken.iter().copied().max().unwrap_or(0),
            },
            "invalid_samples": self.acc.invalid_samples(),
            "per_part": self.parts.iter().map(|p| json!({
                "part": p.part.label(),
                "host": p.stats.host,
                "threads": p.stats.threads,
                "render_s": p.stats.render_s,
                "wall_s": p.stats.wall_s,
                "rays": p.stats.rays(),
            })).collect::<Vec<_>>(),
        })
    }
}
