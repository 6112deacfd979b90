//! OBJ files of positions and faces only (what scanners and mesh converters write: `v x y z`,
//! `f i j k ...` with plain or negative indices, comments) parsed in parallel: the text is cut
//! at line ends into chunks, a first pass counts each chunk's vertices and triangles, a
//! second parses every chunk into its own part of the arrays. Any other statement (uvs,
//! normals, groups, materials, `v` with colours) and any line it cannot read make it decline:
//! tobj then reads the file and reports errors with their line.

use crate::scene::Mesh;
use glam::Vec3;
use rayon::prelude::*;

/// What one chunk holds: vertices and triangles.
#[derive(Clone, Copy, Default)]
struct Counts {
    v: usize,
    t: usize,
}

/// Lines of `chunk` that matter: (keyword, rest), comments and blank lines dropped.
fn statements(chunk: &str) -> impl Iterator<Item = (&str, &str)> {
    chunk.lines().filter_map(|l| {
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') {
            return None;
        }
        Some(l.split_once(char::is_whitespace).unwrap_or((l, "")))
    })
}

/// The chunk's counts, or `None` when it holds anything this reader does not take.
fn count(chunk: &str) -> Option<Counts> {
    let mut c = Counts::default();
    for (key, rest) in statements(chunk) {
        match key {
            "v" => c.v += 1,
            "f" => {
                let n = rest.split_whitespace().count();
                if n < 3 || rest.contains('/') {
                    return None;
                }
                c.t += n - 2;
            }
            _ => return None,
        }
    }
    Some(c)
}

/// Cuts `text` into about `n` pieces at line ends.
fn chunks(text: &str, n: usize) -> Vec<&str> {
    let bytes = text.as_bytes();
    let step = (text.len() / n.max(1)).max(1 << 16);
    let mut out = Vec::new();
    let mut start = 0;
    while start < text.len() {
        let mut end = (start + step).min(text.len());
        while end < text.len() && bytes[end - 1] != b'\n' {
            end += 1;
        }
        out.push(&text[start..end]);
        start = end;
    }
    out
}

/// The mesh of a positions-and-faces OBJ, or `None` when the file holds more (or something
/// unreadable): then tobj reads it.
pub fn parse(text: &str) -> Option<Mesh> {
    let parts = chunks(text, rayon::current_num_threads() * 8);
    let counts: Vec<Counts> = parts.par_iter().map(|c| count(c)).collect::<Option<_>>()?;
    // Where each chunk's vertices and triangles start.
    let mut starts = Vec::with_capacity(counts.len());
    let mut total = Counts::default();
    for c in &counts {
        starts.push(total);
        total.v += c.v;
        total.t += c.t;
    }
    let mut positions = vec![Vec3::ZERO; total.v];
    let mut triangles = vec![[0u32; 3]; total.t];
    // Split the outputs into the chunks' disjoint parts.
    let mut p_rest: &mut [Vec3] = &mut positions;
    let mut t_rest: &mut [[u32; 3]] = &mut triangles;
    let mut jobs = Vec::with_capacity(parts.len());
    for ((chunk, c), s) in parts.iter().zip(&counts).zip(&starts) {
        let (p, pr) = std::mem::take(&mut p_rest).split_at_mut(c.v);
        let (t, tr) = std::mem::take(&mut t_rest).split_at_mut(c.t);
        (p_rest, t_rest) = (pr, tr);
        jobs.push((*chunk, p, t, s.v));
    }
    let n = total.v as i64;
    // Per chunk: whether every statement read (one that does not declines the whole file).
    let ok = jobs.into_par_iter().all(|(chunk, p, t, v_before)| {
        let (mut vi, mut ti) = (0usize, 0usize);
        for (key, rest) in statements(chunk) {
            if key == "v" {
                let mut w = rest.split_whitespace().map(str::parse::<f32>);
                let (Some(Ok(x)), Some(Ok(y)), Some(Ok(z)), None) = (w.next(), w.next(), w.next(), w.next()) else {
                    return false;
                };
                let q = Vec3::new(x, y, z);
                if !q.is_finite() {
                    return false;
                }
                p[vi] = q;
                vi += 1;
            } else {
                // 1-based, or negative: relative to the vertices read so far.
                let seen = (v_before + vi) as i64;
                let mut idx = rest.split_whitespace().map(|s| match s.parse::<i64>() {
                    Ok(i) if i > 0 && i <= n => Some((i - 1) as u32),
                    Ok(i) if i < 0 && -i <= seen => Some((seen + i) as u32),
                    _ => None,
                });
                let (Some(Some(a)), Some(Some(mut b))) = (idx.next(), idx.next()) else { return false };
                for c in idx {
                    let Some(c) = c else { return false };
                    t[ti] = [a, b, c];
                    ti += 1;
                    b = c;
                }
            }
        }
        true
    });
    if !ok {
        return None;
    }
    if triangles.is_empty() {
        return None;
    }
    let material_ids = crate::scene::MaterialIds::uniform(0, triangles.len());
    Some(Mesh { positions, normals: None, uvs: None, colors: None, tangents: None, triangles, material_ids })
}
