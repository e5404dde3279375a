//! The fast path of one pair or one shape (pypw85's scalar calls): the arguments read straight
//! from the Python objects, the row evaluated by the same code as the vectorised path, the
//! result built without NumPy's conversions. A vectorised call of one row spends most of its
//! time in `np.asarray`, the shape checks and the borrows of the matrices, for about 0.1 µs of
//! arithmetic.
//!
//! Only values that the vectorised path would take without changing them are read here: Python
//! floats and NumPy float64 scalars, Python ints within int64, exact lists and tuples of those,
//! and float64 ndarrays of exactly the scalar shape (any strides). Anything else (other dtypes,
//! batches, bools, subclasses, a wrong shape, an `out` that is not a writeable aligned
//! C-contiguous float64 array of the row's shape or that shares memory with an input) makes
//! [`_one`] return None, and the Python wrapper goes the vectorised way, which converts the
//! value or raises the error it always raised. Errors in the values (NaN, a form that is not
//! positive definite, ...) come from the same row code, with the same message.

use crate::rows::{Input, Kind, evaluate};
use numpy::npyffi::{self, NPY_ARRAY_ALIGNED, NPY_ARRAY_C_CONTIGUOUS, NPY_ARRAY_WRITEABLE};
use numpy::{PyArray1, PyArrayDescrMethods, PyUntypedArray, PyUntypedArrayMethods, dtype};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyTuple};

/// The most values one call reads (`overlap_measure` in 3D: 2 × (3 + 3 + 4)).
const MOST_VALUES: usize = 20;

/// The most arguments of a kind (`overlap_measure`: ci, ai, oi, cj, aj, oj).
const MOST_ARGUMENTS: usize = 6;

/// The widest output row (`contact_details`).
const WIDEST: usize = 23;

/// The bytes `[start, end)` an ndarray's values span, as `np.may_share_memory` bounds them.
type Extent = (usize, usize);

/// The shape of each argument of a scalar call of `kind` (`[]`: a number), or None for a kind
/// without a fast path.
fn scalar_shapes(kind: Kind) -> Option<&'static [&'static [usize]]> {
    Some(match kind {
        Kind::Contact3 | Kind::Overlap3 | Kind::Details3 => &[&[3], &[6], &[6]],
        Kind::Contact2 | Kind::Overlap2 | Kind::Details2 => &[&[2], &[3], &[3]],
        Kind::FNeg3 => &[&[], &[3], &[6], &[6]],
        Kind::Spheroid => &[&[], &[], &[3]],
        Kind::AxesQuaternion => &[&[3], &[4]],
        Kind::AxesRotation => &[&[3], &[3, 3]],
        Kind::AxesAngle2d => &[&[2], &[]],
        // The arguments of the measure are laid out side by side as its one input row.
        Kind::Measure3 => &[&[3], &[3], &[4], &[3], &[3], &[4]],
        Kind::Measure2 => &[&[2], &[2], &[], &[2], &[2], &[]],
    })
}

/// Whether the arguments of `kind` make one input row together (the overlap measure's pair).
fn one_input(kind: Kind) -> bool {
    matches!(kind, Kind::Measure3 | Kind::Measure2)
}

/// `obj` as a NumPy array of native float64, when it is one.
fn float64_array<'a, 'py>(obj: &'a Bound<'py, PyAny>) -> Option<&'a Bound<'py, PyUntypedArray>> {
    let array = obj.cast::<PyUntypedArray>().ok()?;
    let descr = array.dtype();
    (descr.num() == npyffi::NPY_TYPES::NPY_DOUBLE as std::ffi::c_int
        && descr.is_native_byteorder() != Some(false))
    .then_some(array)
}

/// Reads the number `obj` when it is a Python float, a NumPy float64 scalar or a Python int
/// within int64 (converted as NumPy converts int64 to float64: to the nearest).
fn read_number(obj: &Bound<'_, PyAny>) -> Option<f64> {
    if obj.is_exact_instance_of::<PyFloat>() {
        // SAFETY: an exact float.
        return Some(unsafe { obj.cast_unchecked::<PyFloat>() }.value());
    }
    if obj.is_exact_instance_of::<PyInt>() {
        return obj.extract::<i64>().ok().map(|i| i as f64);
    }
    // Of float's subclasses, only np.float64 (bool, an int subclass, is never read).
    if obj.is_instance_of::<PyFloat>() && obj.get_type().is(dtype::<f64>(obj.py()).typeobj()) {
        // SAFETY: a float subclass.
        return Some(unsafe { obj.cast_unchecked::<PyFloat>() }.value());
    }
    None
}

/// Reads `obj` into `out` (its values in C order) when it is an array of shape `shape` that
/// the vectorised path would take without changing a value: a number (shape `[]`), an exact
/// ndarray of native float64 of that shape, or an exact list or tuple of such rows (or numbers). `extent`
/// receives the bytes of an ndarray's values. False for anything else.
fn read(
    obj: &Bound<'_, PyAny>,
    shape: &[usize],
    out: &mut [f64],
    extent: &mut Option<Extent>,
) -> bool {
    // SAFETY: only the type of `obj` is compared.
    if unsafe { npyffi::PyArray_CheckExact(obj.py(), obj.as_ptr()) } != 0 {
        let Some(array) = float64_array(obj) else {
            return false;
        };
        if array.shape() != shape {
            return false;
        }
        // SAFETY: the array's own fields, read with the GIL held.
        let data = unsafe { (*npyffi::_PyArray_GET_ITEM_DATA(array.as_array_ptr())).data };
        let strides = array.strides();
        let (mut low, mut high) = (0isize, 0isize);
        for (&n, &s) in shape.iter().zip(strides) {
            let span = (n as isize - 1) * s;
            low += span.min(0);
            high += span.max(0);
        }
        let start = data as usize;
        *extent = Some((
            start.wrapping_add_signed(low),
            start.wrapping_add_signed(high) + 8,
        ));
        // C order over at most two axes, each value read unaligned: any strides, any offset.
        let (rows, columns) = match *shape {
            [] => (1, 1),
            [n] => (1, n),
            [m, n] => (m, n),
            _ => return false,
        };
        let (row_stride, column_stride) = match *strides {
            [] => (0, 0),
            [s] => (0, s),
            [r, s] => (r, s),
            _ => return false,
        };
        for i in 0..rows {
            for j in 0..columns {
                let offset = i as isize * row_stride + j as isize * column_stride;
                // SAFETY: (i, j) is inside the array's shape, so data + offset is one of its
                // float64 values.
                out[i * columns + j] =
                    unsafe { data.offset(offset).cast::<f64>().read_unaligned() };
            }
        }
        return true;
    }
    let Some((&n, row)) = shape.split_first() else {
        return match read_number(obj) {
            Some(x) => {
                out[0] = x;
                true
            }
            None => false,
        };
    };
    let width = out.len() / n;
    // The rows of a list are copied by NumPy: their memory is not the argument's.
    let mut item = |k: usize, value: &Bound<'_, PyAny>| {
        read(value, row, &mut out[k * width..(k + 1) * width], &mut None)
    };
    if let Ok(list) = obj.cast_exact::<PyList>() {
        list.len() == n && (0..n).all(|k| list.get_item(k).is_ok_and(|v| item(k, &v)))
    } else if let Ok(tuple) = obj.cast_exact::<PyTuple>() {
        tuple.len() == n && (0..n).all(|k| tuple.get_borrowed_item(k).is_ok_and(|v| item(k, &v)))
    } else {
        false
    }
}

/// `out` as the writeable, aligned, C-contiguous float64 array of `width` values that does not
/// share memory with an input (`extents`), or None.
fn out_row<'a, 'py>(
    out: &'a Bound<'py, PyAny>,
    width: usize,
    extents: &[Option<Extent>],
) -> Option<&'a Bound<'py, PyUntypedArray>> {
    let array = float64_array(out)?;
    let wanted = NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED | NPY_ARRAY_WRITEABLE;
    // SAFETY: the array's own fields, read with the GIL held.
    let fields = unsafe { &*npyffi::_PyArray_GET_ITEM_DATA(array.as_array_ptr()) };
    if array.shape() != [width] || fields.flags & wanted != wanted {
        return None;
    }
    let start = fields.data as usize;
    let end = start + 8 * width;
    let shared = extents
        .iter()
        .flatten()
        .any(|&(low, high)| low < end && start < high);
    (!shared).then_some(array)
}

/// `_one(kind, out, *args)`: the row kernel `kind` on one row given as Python objects, `out`
/// (or None) receiving the output row; None when an argument or `out` is not one the fast path
/// reads (see the module's documentation), and the caller then takes the vectorised path.
///
/// Returns `(mu2, lam)` for a contact function, a bool for an overlap, a float for `f_neg3`,
/// the output row (a new float64 array, or `out` filled) otherwise. The overlap measure's
/// arguments are `ci, ai, oi, cj, aj, oj` (`measure3`: (3,), (3,), (4,); `measure2`: (2,),
/// (2,), a number).
#[pyfunction]
#[pyo3(signature = (kind, out, *args))]
pub fn _one<'py>(
    py: Python<'py>,
    kind: &str,
    out: Option<&Bound<'py, PyAny>>,
    args: &Bound<'py, PyTuple>,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    let kind = Kind::from_name(kind)?;
    let Some(shapes) = scalar_shapes(kind) else {
        return Ok(None);
    };
    if args.len() != shapes.len() {
        return Err(PyValueError::new_err(format!(
            "{} arguments where the kernel takes {}",
            args.len(),
            shapes.len()
        )));
    }
    let mut values = [0.0; MOST_VALUES];
    let mut extents = [None; MOST_ARGUMENTS];
    let mut ends = [0; MOST_ARGUMENTS];
    let mut end = 0;
    for (k, shape) in shapes.iter().enumerate() {
        let start = end;
        end += shape.iter().product::<usize>();
        let arg = args.get_borrowed_item(k)?;
        if !read(&arg, shape, &mut values[start..end], &mut extents[k]) {
            return Ok(None);
        }
        ends[k] = end;
    }
    let width = kind.output_width();
    let out = match out {
        None => None,
        // A verdict's `out` is a bool array: the vectorised path fills it.
        Some(_) if matches!(kind, Kind::Overlap3 | Kind::Overlap2) => return Ok(None),
        Some(o) => match out_row(o, width, &extents) {
            Some(array) => Some(array),
            None => return Ok(None),
        },
    };
    let mut inputs = [Input {
        data: &[],
        stride: 0,
    }; MOST_ARGUMENTS];
    let arguments = if one_input(kind) {
        inputs[0].data = &values[..end];
        1
    } else {
        let mut start = 0;
        for (input, &end) in inputs.iter_mut().zip(&ends[..shapes.len()]) {
            input.data = &values[start..end];
            start = end;
        }
        shapes.len()
    };
    let mut row = [0.0; WIDEST];
    let row = &mut row[..width];
    // The vectorised path's own evaluation of one row: the same results and messages.
    evaluate(kind, &inputs[..arguments], row, 1, None)
        .map_err(|e| PyValueError::new_err(e.message))?;
    if let Some(array) = out {
        // SAFETY: `out_row` checked a writeable, aligned, C-contiguous float64 array of
        // `width` values; the GIL is held and nothing else refers to these bytes here.
        unsafe {
            let data = (*npyffi::_PyArray_GET_ITEM_DATA(array.as_array_ptr()))
                .data
                .cast::<f64>();
            std::ptr::copy_nonoverlapping(row.as_ptr(), data, width);
        }
    }
    Ok(Some(match kind {
        Kind::Contact3 | Kind::Contact2 => (row[0], row[1]).into_pyobject(py)?.into_any(),
        Kind::Overlap3 | Kind::Overlap2 => PyBool::new(py, row[0] != 0.0).to_owned().into_any(),
        Kind::FNeg3 => PyFloat::new(py, row[0]).into_any(),
        _ => match out {
            Some(array) => array.clone().into_any(),
            None => PyArray1::from_slice(py, row).into_any(),
        },
    }))
}
