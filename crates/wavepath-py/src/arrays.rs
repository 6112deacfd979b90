//! numpy arrays in and out. Inputs are read where they lie (any dtype the engine can take
//! without loss, C- or Fortran-ordered, strided) and converted once, element by element,
//! into the engine's types; outputs are Rust vectors handed to numpy without a copy.

use crate::errors::value_error;
use glam::Vec3;
use numpy::ndarray::{ArrayView1, ArrayView2, s};
use numpy::{PyArrayDescrMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// An `(n, k)` array of floats, as given (float32 or float64; other real dtypes converted).
pub enum Floats<'py> {
    F32(PyReadonlyArray2<'py, f32>),
    F64(PyReadonlyArray2<'py, f64>),
}

/// A borrowed view of [`Floats`] that can cross into threads without the GIL.
#[derive(Clone, Copy)]
pub enum FloatRows<'a> {
    F32(ArrayView2<'a, f32>),
    F64(ArrayView2<'a, f64>),
}

impl<'py> Floats<'py> {
    pub fn rows(&self) -> FloatRows<'_> {
        match self {
            Floats::F32(a) => FloatRows::F32(a.as_array()),
            Floats::F64(a) => FloatRows::F64(a.as_array()),
        }
    }
}

impl FloatRows<'_> {
    pub fn len(&self) -> usize {
        match self {
            FloatRows::F32(a) => a.nrows(),
            FloatRows::F64(a) => a.nrows(),
        }
    }

    /// Row `i` as a point or direction (the first three columns).
    #[inline]
    pub fn vec3(&self, i: usize) -> Vec3 {
        match self {
            FloatRows::F32(a) => Vec3::new(a[[i, 0]], a[[i, 1]], a[[i, 2]]),
            FloatRows::F64(a) => Vec3::new(a[[i, 0]] as f32, a[[i, 1]] as f32, a[[i, 2]] as f32),
        }
    }

    /// Row `i`, column `j`.
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f32 {
        match self {
            FloatRows::F32(a) => a[[i, j]],
            FloatRows::F64(a) => a[[i, j]] as f32,
        }
    }

    /// Rows `start..start + n` as one flat float32 slice of `3 n` values, when the array is
    /// float32 and those rows are C-contiguous (the common case: no conversion needed).
    pub fn f32_rows(&self, start: usize, n: usize) -> Option<&[f32]> {
        match self {
            FloatRows::F32(a) => a.slice(s![start..start + n, ..]).to_slice(),
            FloatRows::F64(_) => None,
        }
    }

    /// Rows `start..start + out.len()` of a three-column array into `out`: the dtype is
    /// chosen once per call and C-contiguous rows are read as one flat slice, so the
    /// per-ray cost is a load and a store, not a match and three bounds checks.
    pub fn read_vec3s(&self, start: usize, out: &mut [Vec3]) {
        match self {
            FloatRows::F32(a) => rows3(a, start, out),
            FloatRows::F64(a) => rows3(a, start, out),
        }
    }
}

/// The real types numpy arrays arrive in, read as the engine's f32.
pub trait Real: Copy {
    fn to_f32(self) -> f32;
}

impl Real for f32 {
    #[inline]
    fn to_f32(self) -> f32 {
        self
    }
}

impl Real for f64 {
    #[inline]
    fn to_f32(self) -> f32 {
        self as f32
    }
}

fn rows3<T: Real>(a: &ArrayView2<'_, T>, start: usize, out: &mut [Vec3]) {
    let rows = a.slice(s![start..start + out.len(), ..]);
    if let Some(flat) = rows.as_slice() {
        for (v, c) in out.iter_mut().zip(flat.chunks_exact(3)) {
            *v = Vec3::new(c[0].to_f32(), c[1].to_f32(), c[2].to_f32());
        }
    } else {
        for (v, r) in out.iter_mut().zip(rows.outer_iter()) {
            *v = Vec3::new(r[0].to_f32(), r[1].to_f32(), r[2].to_f32());
        }
    }
}

fn values<T: Real>(a: &ArrayView1<'_, T>, start: usize, out: &mut [f32]) {
    let part = a.slice(s![start..start + out.len()]);
    match part.as_slice() {
        Some(flat) => out.iter_mut().zip(flat).for_each(|(o, v)| *o = v.to_f32()),
        None => out.iter_mut().zip(part.iter()).for_each(|(o, v)| *o = v.to_f32()),
    }
}

/// A per-ray value: one number for every ray, or an `(n,)` array.
pub enum PerRay<'py> {
    All(f32),
    F32(PyReadonlyArray1<'py, f32>),
    F64(PyReadonlyArray1<'py, f64>),
}

#[derive(Clone, Copy)]
pub enum PerRayView<'a> {
    All(f32),
    F32(ArrayView1<'a, f32>),
    F64(ArrayView1<'a, f64>),
}

impl PerRay<'_> {
    pub fn view(&self) -> PerRayView<'_> {
        match self {
            PerRay::All(v) => PerRayView::All(*v),
            PerRay::F32(a) => PerRayView::F32(a.as_array()),
            PerRay::F64(a) => PerRayView::F64(a.as_array()),
        }
    }
}

impl PerRayView<'_> {
    /// Values `start..start + n` as a float32 slice, when they are one (or `None`).
    pub fn f32_values(&self, start: usize, n: usize) -> Option<&[f32]> {
        match self {
            PerRayView::F32(a) => a.slice(s![start..start + n]).to_slice(),
            _ => None,
        }
    }

    /// Values `start..start + out.len()` into `out` (the dtype chosen once per call).
    pub fn read(&self, start: usize, out: &mut [f32]) {
        match self {
            PerRayView::All(v) => out.fill(*v),
            PerRayView::F32(a) => values(a, start, out),
            PerRayView::F64(a) => values(a, start, out),
        }
    }
}

fn numpy_asarray<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Bound<'py, PyAny>> {
    let np = obj.py().import("numpy")?;
    np.call_method1("asarray", (obj,))
        .map_err(|_| value_error(format!("{name} is not an array or a sequence of numbers")))
}

fn shape_text(a: &Bound<'_, PyUntypedArray>) -> String {
    let s: Vec<String> = a.shape().iter().map(|d| d.to_string()).collect();
    if s.len() == 1 { format!("({},)", s[0]) } else { format!("({})", s.join(", ")) }
}

/// The array's dtype kind (`f`, `i`, `u`, `b`, ...) and item size in bytes.
fn kind_of(a: &Bound<'_, PyUntypedArray>) -> (u8, usize) {
    let d = a.dtype();
    (d.kind(), d.itemsize())
}

/// Reads `obj` as an `(n, cols)` float array: float32 and float64 as they are, other real
/// numbers (integers, float16) converted to float64 once.
pub fn floats<'py>(obj: &Bound<'py, PyAny>, name: &str, cols: usize) -> PyResult<Floats<'py>> {
    let obj = if obj.cast::<PyUntypedArray>().is_ok() { obj.clone() } else { numpy_asarray(obj, name)? };
    let a = obj.cast::<PyUntypedArray>().map_err(|_| value_error(format!("{name} is not an array")))?;
    if a.ndim() != 2 || a.shape()[1] != cols {
        return Err(value_error(format!("{name} must have shape (n, {cols}), got shape {}", shape_text(a))));
    }
    match kind_of(a) {
        (b'f', 4) => Ok(Floats::F32(obj.extract()?)),
        (b'f', 8) => Ok(Floats::F64(obj.extract()?)),
        (b'f' | b'i' | b'u', _) => Ok(Floats::F64(obj.call_method1("astype", ("float64",))?.extract()?)),
        _ => Err(value_error(format!("{name} must be a float32 or float64 array, got dtype {}", a.dtype()))),
    }
}

/// Reads `obj` as an `(n,)` array of floats, or one number for all `n`.
pub fn per_ray<'py>(obj: &Bound<'py, PyAny>, name: &str, n: usize) -> PyResult<PerRay<'py>> {
    if let Ok(v) = obj.extract::<f64>() {
        return Ok(PerRay::All(v as f32));
    }
    let obj = if obj.cast::<PyUntypedArray>().is_ok() { obj.clone() } else { numpy_asarray(obj, name)? };
    let a = obj.cast::<PyUntypedArray>().map_err(|_| value_error(format!("{name} is not an array")))?;
    if a.ndim() != 1 || a.shape()[0] != n {
        return Err(value_error(format!("{name} must be a number or have shape ({n},), got shape {}", shape_text(a))));
    }
    match kind_of(a) {
        (b'f', 4) => Ok(PerRay::F32(obj.extract()?)),
        (b'f', 8) => Ok(PerRay::F64(obj.extract()?)),
        (b'f' | b'i' | b'u', _) => Ok(PerRay::F64(obj.call_method1("astype", ("float64",))?.extract()?)),
        _ => Err(value_error(format!("{name} must be float32 or float64, got dtype {}", a.dtype()))),
    }
}

/// Reads `obj` as an `(m, cols)` array of non-negative integers (vertex or material
/// indices), checked and converted to u32.
pub fn indices(obj: &Bound<'_, PyAny>, name: &str, cols: Option<usize>) -> PyResult<Vec<u32>> {
    let obj = if obj.cast::<PyUntypedArray>().is_ok() { obj.clone() } else { numpy_asarray(obj, name)? };
    let a = obj.cast::<PyUntypedArray>().map_err(|_| value_error(format!("{name} is not an array")))?;
    let shape_ok = match cols {
        Some(c) => a.ndim() == 2 && a.shape()[1] == c,
        None => a.ndim() == 1,
    };
    if !shape_ok {
        let want = cols.map_or("(m,)".to_string(), |c| format!("(m, {c})"));
        return Err(value_error(format!("{name} must have shape {want}, got shape {}", shape_text(a))));
    }
    if !matches!(kind_of(a).0, b'i' | b'u') {
        return Err(value_error(format!("{name} must be an integer array, got dtype {}", a.dtype())));
    }
    let flat = obj.call_method1("astype", ("int64",))?.call_method0("ravel")?;
    let v: PyReadonlyArray1<'_, i64> = flat.extract()?;
    let v = v.as_array();
    let per = cols.unwrap_or(1);
    let mut out = Vec::with_capacity(v.len());
    for (i, &x) in v.iter().enumerate() {
        if !(0..=u32::MAX as i64 - 1).contains(&x) {
            return Err(value_error(format!("{name}: row {} holds {x}, not an index", i / per)));
        }
        out.push(x as u32);
    }
    Ok(out)
}
