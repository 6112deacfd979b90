//! Which part of a render one process takes: part I of N, split by image bands or by
//! sample ranges.

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use wavepath::{Cell, Settings};

/// How a render is cut into parts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// Bands of rows, dealt round-robin to the parts: every pixel is rendered by one part
    /// exactly as a single process renders it, so the merge is bit-identical.
    #[default]
    Tiles,
    /// Every part renders every pixel with its own range of sample indices; the merge adds
    /// the per-pixel sums (identical up to floating-point summation order).
    Samples,
}

impl Split {
    pub fn name(self) -> &'static str {
        match self {
            Split::Tiles => "tiles",
            Split::Samples => "samples",
        }
    }
}

/// Part `index` (0-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PartSpec {
    pub index: u32,
    pub count: u32,
    pub split: Split,
}

/// Most parts accepted: far more than any array job here, few enough to catch typos.
pub const MAX_PARTS: u32 = 1 << 16;

/// The environment variable that gives N for `--part auto` under a Kubernetes Indexed Job
/// (which sets only the index, `JOB_COMPLETION_INDEX`).
pub const PARTS_ENV: &str = "WAVEPATH_PARTS";

impl PartSpec {
    pub fn new(index: u32, count: u32, split: Split) -> Result<Self> {
        if count == 0 || count > MAX_PARTS {
            bail!("--part: the number of parts must be between 1 and {MAX_PARTS}, got {count}");
        }
        if index >= count {
            bail!("--part {index}/{count}: the index must be below the number of parts (0-based)");
        }
        Ok(PartSpec { index, count, split })
    }

    /// Parses `I/N` or `auto`; `auto` reads the scheduler's environment through `env`
    /// (Slurm array: `SLURM_ARRAY_TASK_ID` - `SLURM_ARRAY_TASK_MIN` of
    /// `SLURM_ARRAY_TASK_COUNT`; Kubernetes Indexed Job: `JOB_COMPLETION_INDEX` of
    /// `parts` or `WAVEPATH_PARTS`).
    pub fn parse(text: &str, parts: Option<u32>, split: Split, env: &dyn Fn(&str) -> Option<String>) -> Result<Self> {
        let num = |name: &str, v: &str| -> Result<u32> {
            v.trim().parse::<u32>().with_context(|| format!("{name}={v:?} is not a whole number"))
        };
        if text != "auto" {
            let (i, n) = text.split_once('/').with_context(|| format!("--part {text:?}: expected I/N or auto"))?;
            let i = i.trim().parse().with_context(|| format!("--part {text:?}: I is not a whole number"))?;
            let n = n.trim().parse().with_context(|| format!("--part {text:?}: N is not a whole number"))?;
            return PartSpec::new(i, n, split);
        }
        if let Some(id) = env("SLURM_ARRAY_TASK_ID") {
            let id = num("SLURM_ARRAY_TASK_ID", &id)?;
            let min = match env("SLURM_ARRAY_TASK_MIN") {
                Some(m) => num("SLURM_ARRAY_TASK_MIN", &m)?,
                None => 0,
            };
            let count = env("SLURM_ARRAY_TASK_COUNT")
                .context("--part auto: SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")?;
            let count = num("SLURM_ARRAY_TASK_COUNT", &count)?;
            if id < min {
                bail!("--part auto: SLURM_ARRAY_TASK_ID={id} is below SLURM_ARRAY_TASK_MIN={min}");
            }
            return PartSpec::new(id - min, count, split)
                .context("--part auto: the array must be contiguous (--array=0-(N-1), no step)");
        }
        if let Some(i) = env("JOB_COMPLETION_INDEX") {
            let i = num("JOB_COMPLETION_INDEX", &i)?;
            let n = match (parts, env(PARTS_ENV)) {
                (Some(n), _) => n,
                (None, Some(n)) => num(PARTS_ENV, &n)?,
                (None, None) => bail!("--part auto: JOB_COMPLETION_INDEX is set; give N with --parts N or {PARTS_ENV}"),
            };
            return PartSpec::new(i, n, split);
        }
        bail!("--part auto: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set (not in an array job?)")
    }

    /// The text form, `I/N`.
    pub fn label(&self) -> String {
        format!("{}/{}", self.index, self.count)
    }

    /// Checks that the settings can be split this way.
    pub fn check(&self, s: &Settings) -> Result<()> {
        if s.image.cell.is_some() {
            bail!("--part cannot be combined with -p (a part already chooses its own pixels)");
        }
        if s.paths.shading == wavepath::Shading::Normals {
            bail!("--part renders light transport only; --shading normals has no sums to merge");
        }
        if self.split == Split::Samples {
            if s.sampling.adaptive.is_some() {
                bail!(
                    "--split samples cannot be used with adaptive sampling (-a): whether a pixel stops \
                     depends on all its earlier samples, which other parts take; use --split tiles"
                );
            }
            if s.sampling.spp < self.count {
                bail!(
                    "--split samples with {} parts needs at least {} samples per pixel (-s), got {}",
                    self.count,
                    self.count,
                    s.sampling.spp
                );
            }
        }
        Ok(())
    }

    /// Sample indices `[first, end)` this part takes (all of them for tiles).
    pub fn sample_range(&self, spp: u32) -> (u32, u32) {
        match self.split {
            Split::Tiles => (0, spp),
            Split::Samples => {
                let at = |i: u32| (i as u64 * spp as u64 / self.count as u64) as u32;
                (at(self.index), at(self.index + 1))
            }
        }
    }

    /// Rows per band for tiles: about four bands per part so uneven rows even out, at most
    /// 16 rows so bands stay small next to the image.
    pub fn band_rows(&self, height: usize) -> usize {
        height.div_ceil(4 * self.count as usize).clamp(1, 16)
    }

    /// Whether row `y` (bottom-origin) belongs to this part.
    pub fn owns_row(&self, y: usize, height: usize) -> bool {
        match self.split {
            Split::Tiles => (y / self.band_rows(height)) % self.count as usize == self.index as usize,
            Split::Samples => true,
        }
    }

    /// The rectangles this part renders: runs of consecutive owned rows, full width.
    pub fn cells(&self, width: usize, height: usize) -> Vec<Cell> {
        let mut cells: Vec<Cell> = Vec::new();
        for y in (0..height).filter(|&y| self.owns_row(y, height)) {
            match cells.last_mut() {
                Some(c) if c.y + c.h == y => c.h += 1,
                _ => cells.push(Cell { x: 0, y, w: width, h: 1 }),
            }
        }
        cells
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env_of(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let v: Vec<(String, String)> = pairs.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
        move |k| v.iter().find(|(a, _)| a == k).map(|(_, b)| b.clone())
    }

    #[test]
    fn parses_explicit_and_scheduler_parts() {
        let none = env_of(&[]);
        assert_eq!(
            PartSpec::parse("2/4", None, Split::Tiles, &none).unwrap(),
            PartSpec::new(2, 4, Split::Tiles).unwrap()
        );
        assert!(PartSpec::parse("4/4", None, Split::Tiles, &none).is_err());
        assert!(PartSpec::parse("x/4", None, Split::Tiles, &none).is_err());
        assert!(PartSpec::parse("auto", None, Split::Tiles, &none).is_err());
        let slurm =
            env_of(&[("SLURM_ARRAY_TASK_ID", "5"), ("SLURM_ARRAY_TASK_MIN", "4"), ("SLURM_ARRAY_TASK_COUNT", "3")]);
        assert_eq!(PartSpec::parse("auto", None, Split::Samples, &slurm).unwrap().label(), "1/3");
        let k8s = env_of(&[("JOB_COMPLETION_INDEX", "2")]);
        assert!(PartSpec::parse("auto", None, Split::Tiles, &k8s).is_err(), "no N anywhere");
        assert_eq!(PartSpec::parse("auto", Some(8), Split::Tiles, &k8s).unwrap().label(), "2/8");
        let k8s_env = env_of(&[("JOB_COMPLETION_INDEX", "2"), (PARTS_ENV, "3")]);
        assert_eq!(PartSpec::parse("auto", None, Split::Tiles, &k8s_env).unwrap().label(), "2/3");
    }

    #[test]
    fn tiles_cover_every_row_once_and_sample_ranges_tile_the_samples() {
        for n in [1u32, 2, 3, 4, 7, 50] {
            for h in [1usize, 5, 48, 361] {
                let mut seen = vec![0; h];
                for i in 0..n {
                    let p = PartSpec::new(i, n, Split::Tiles).unwrap();
                    for c in p.cells(9, h) {
                        for k in &mut seen[c.y..c.y + c.h] {
                            *k += 1;
                        }
                    }
                }
                assert!(seen.iter().all(|&k| k == 1), "n={n} h={h}");
            }
            let spp = 67;
            let mut next = 0;
            for i in 0..n.min(spp) {
                let (a, b) = PartSpec::new(i, n.min(spp), Split::Samples).unwrap().sample_range(spp);
                assert_eq!(a, next);
                next = b;
            }
            assert_eq!(next, spp);
        }
        assert_eq!(PartSpec::new(0, 1, Split::Tiles).unwrap().cells(4, 100).len(), 1, "one part: one render");
    }
}
