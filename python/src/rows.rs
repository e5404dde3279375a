//! Row-wise evaluation: every vectorised function of the package is one [`Kind`] mapping rows of
//! its inputs to a row of its output. The Python layer (`ellipack/__init__.py`) turns what the
//! user passed into C-contiguous float64 matrices (one row, broadcast, or n rows); here the
//! rows are cut into chunks, evaluated by the Rust crates on the calling thread or a rayon pool,
//! with the GIL released.

use numpy::{PyReadonlyArray2, PyReadwriteArray2, PyUntypedArrayMethods};
use pw85::batch::{Pair, Pair2d, Parallelism, contact_functions, overlaps};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Rows per chunk: small enough that a chunk's pairs stay in L1/L2 and the threads balance,
/// large enough that the per-chunk work (one batch call) is negligible.
const CHUNK: usize = 256;

/// What a row-wise call computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    Contact3,
    Contact2,
    Overlap3,
    Overlap2,
    Details3,
    Details2,
    FNeg3,
    Spheroid,
    AxesQuaternion,
    AxesRotation,
    AxesAngle2d,
    Measure3,
    Measure2,
}

impl Kind {
    pub(crate) fn from_name(name: &str) -> PyResult<Kind> {
        Ok(match name {
            "contact3" => Kind::Contact3,
            "contact2" => Kind::Contact2,
            "overlap3" => Kind::Overlap3,
            "overlap2" => Kind::Overlap2,
            "details3" => Kind::Details3,
            "details2" => Kind::Details2,
            "f_neg3" => Kind::FNeg3,
            "spheroid" => Kind::Spheroid,
            "axes_quaternion" => Kind::AxesQuaternion,
            "axes_rotation" => Kind::AxesRotation,
            "axes_angle_2d" => Kind::AxesAngle2d,
            "measure3" => Kind::Measure3,
            "measure2" => Kind::Measure2,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "unknown row kernel `{name}`"
                )));
            }
        })
    }

    /// The width of each input row, in the order of the arguments.
    fn input_widths(self) -> &'static [usize] {
        match self {
            Kind::Contact3 | Kind::Overlap3 | Kind::Details3 => &[3, 6, 6],
            Kind::Contact2 | Kind::Overlap2 | Kind::Details2 => &[2, 3, 3],
            Kind::FNeg3 => &[1, 3, 6, 6],
            Kind::Spheroid => &[1, 1, 3],
            Kind::AxesQuaternion => &[3, 4],
            Kind::AxesRotation => &[3, 9],
            Kind::AxesAngle2d => &[2, 1],
            Kind::Measure3 => &[20],
            Kind::Measure2 => &[10],
        }
    }

    /// The width of an output row.
    pub(crate) fn output_width(self) -> usize {
        match self {
            Kind::Contact3 | Kind::Contact2 => 2,
            Kind::Overlap3 | Kind::Overlap2 | Kind::FNeg3 => 1,
            // μ², λ, point, normal, ∂μ²/∂r12, ∂μ²/∂q1, ∂μ²/∂q2.
            Kind::Details3 => 23,
            // The same in 2D: 2 + 2 + 2 + 2 + 3 + 3.
            Kind::Details2 => 14,
            Kind::Spheroid | Kind::AxesQuaternion | Kind::AxesRotation => 6,
            Kind::AxesAngle2d => 3,
            // U, d², ε, f, X, X unique (1 or 0).
            Kind::Measure3 => 8,
            Kind::Measure2 => 7,
        }
    }
}

/// One argument: rows of `width` values, or a single row that every output row reuses
/// (`stride` 0), so that reading a row has no branch.
#[derive(Clone, Copy)]
pub(crate) struct Input<'a> {
    pub(crate) data: &'a [f64],
    pub(crate) stride: usize,
}

impl Input<'_> {
    #[inline(always)]
    fn row<const K: usize>(&self, i: usize) -> [f64; K] {
        let start = i * self.stride;
        let mut row = [0.0; K];
        row.copy_from_slice(&self.data[start..start + K]);
        row
    }

    #[inline(always)]
    fn scalar(&self, i: usize) -> f64 {
        self.data[i * self.stride]
    }
}

/// The first row that could not be evaluated.
pub(crate) struct RowError {
    row: usize,
    pub(crate) message: String,
}

/// The pairs of a chunk and their results, kept from chunk to chunk so that a call allocates
/// once per thread rather than once per chunk.
#[derive(Default)]
struct Buffers {
    pairs: Vec<Pair>,
    pairs_2d: Vec<Pair2d>,
    results: PairResults,
}

/// What pw85's batch functions give for a chunk of pairs, kept between chunks.
#[derive(Default)]
struct PairResults {
    contacts: Vec<Result<pw85::Contact, pw85::Error>>,
    verdicts: Vec<Result<bool, pw85::Error>>,
}

/// Evaluates the rows `start..start + out.len() / width` into `out`.
fn chunk(
    kind: Kind,
    inputs: &[Input<'_>],
    start: usize,
    out: &mut [f64],
    buffers: &mut Buffers,
) -> Result<(), RowError> {
    let width = kind.output_width();
    match kind {
        Kind::Contact3 | Kind::Overlap3 => evaluate_pairs(
            kind,
            inputs,
            start,
            out,
            &mut buffers.pairs,
            &mut buffers.results,
        ),
        Kind::Contact2 | Kind::Overlap2 => evaluate_pairs(
            kind,
            inputs,
            start,
            out,
            &mut buffers.pairs_2d,
            &mut buffers.results,
        ),
        _ => {
            for (i, o) in out.chunks_exact_mut(width).enumerate() {
                one_row(kind, inputs, start + i, o).map_err(|message| RowError {
                    row: start + i,
                    message,
                })?;
            }
            Ok(())
        }
    }
}

/// A pair of pw85's batch functions, read from the r12, q1 and q2 inputs of a row.
trait FromRow: pw85::batch::BatchPair {
    fn from_row(inputs: &[Input<'_>], i: usize) -> Self;
}

macro_rules! from_row {
    ($($pair:ty),*) => {$(
        impl FromRow for $pair {
            #[inline(always)]
            fn from_row(inputs: &[Input<'_>], i: usize) -> Self {
                Self {
                    r12: inputs[0].row(i),
                    q1: inputs[1].row(i),
                    q2: inputs[2].row(i),
                }
            }
        }
    )*};
}

from_row!(Pair, Pair2d);

/// The contact functions or verdicts of the chunk of pairs from row `start` on, through pw85's
/// batch functions; `pairs` and `results` are buffers kept between chunks.
fn evaluate_pairs<P: FromRow>(
    kind: Kind,
    inputs: &[Input<'_>],
    start: usize,
    out: &mut [f64],
    pairs: &mut Vec<P>,
    results: &mut PairResults,
) -> Result<(), RowError> {
    let PairResults { contacts, verdicts } = results;
    let rows = out.len() / kind.output_width();
    pairs.clear();
    pairs.extend((0..rows).map(|i| P::from_row(inputs, start + i)));
    let fail = |i: usize, e: &pw85::Error| RowError {
        row: start + i,
        message: e.to_string(),
    };
    let pairs = &pairs[..];
    if matches!(kind, Kind::Contact3 | Kind::Contact2) {
        contacts.resize(pairs.len(), Ok(pw85::batch::EMPTY_CONTACT));
        contact_functions(pairs, contacts, Parallelism::Serial);
        for (i, (r, o)) in contacts.iter().zip(out.chunks_exact_mut(2)).enumerate() {
            let c = r.as_ref().map_err(|e| fail(i, e))?;
            o.copy_from_slice(&[c.mu2, c.lambda]);
        }
    } else {
        verdicts.resize(pairs.len(), Ok(false));
        overlaps(pairs, verdicts, Parallelism::Serial);
        for (i, (r, o)) in verdicts.iter().zip(out.iter_mut()).enumerate() {
            let overlapping = r.as_ref().map_err(|e| fail(i, e))?;
            *o = f64::from(u8::from(*overlapping));
        }
    }
    Ok(())
}

/// One row of a kind.
fn one_row(kind: Kind, inputs: &[Input<'_>], i: usize, o: &mut [f64]) -> Result<(), String> {
    let text = |e: pw85::Error| e.to_string();
    match kind {
        Kind::Details3 => {
            let d = pw85::contact_details(&inputs[0].row(i), &inputs[1].row(i), &inputs[2].row(i))
                .map_err(text)?;
            o[0] = d.contact.mu2;
            o[1] = d.contact.lambda;
            o[2..5].copy_from_slice(&d.point);
            o[5..8].copy_from_slice(&d.normal);
            o[8..11].copy_from_slice(&d.grad_r12);
            o[11..17].copy_from_slice(&d.grad_q1);
            o[17..23].copy_from_slice(&d.grad_q2);
        }
        Kind::Details2 => {
            let (r, a, b): ([f64; 2], [f64; 3], [f64; 3]) =
                (inputs[0].row(i), inputs[1].row(i), inputs[2].row(i));
            // The ellipses' own contact function checks the input, so that errors name their
            // entries, and gives μ² and λ as `contact_function_2d` does.
            let c = pw85::contact_function::<[f64; 3]>(&r, &a, &b).map_err(text)?;
            // Two ellipses are the z = 0 sections of two ellipsoids with a common third axis
            // along z: with r12 in the plane, Q(λ)⁻¹ r12 stays in the plane and f(λ) is the
            // ellipses' own, so the ellipsoids' point, normal and gradients are the ellipses'
            // with a zero z part. The third axis is scaled like the forms.
            let z = a[0].max(a[2]).max(b[0]).max(b[2]);
            let lift = |q: [f64; 3]| [q[0], q[1], 0.0, q[2], 0.0, z];
            let d = pw85::contact_details(&[r[0], r[1], 0.0], &lift(a), &lift(b)).map_err(text)?;
            let plane = |g: [f64; 6]| [g[0], g[1], g[3]];
            o[0] = c.mu2;
            o[1] = c.lambda;
            o[2..4].copy_from_slice(&d.point[..2]);
            o[4..6].copy_from_slice(&d.normal[..2]);
            o[6..8].copy_from_slice(&d.grad_r12[..2]);
            o[8..11].copy_from_slice(&plane(d.grad_q1));
            o[11..14].copy_from_slice(&plane(d.grad_q2));
        }
        Kind::FNeg3 => {
            let lambda = inputs[0].scalar(i);
            let (r12, q1, q2) = (inputs[1].row(i), inputs[2].row(i), inputs[3].row(i));
            if !(0.0..=1.0).contains(&lambda) {
                return Err(format!("lambda must lie in [0, 1], not {lambda}"));
            }
            o[0] = -pw85::objective(lambda, &r12, &q1, &q2).map_err(text)?;
        }
        Kind::Spheroid => {
            let q = spheroid(inputs[0].scalar(i), inputs[1].scalar(i), &inputs[2].row(i))?;
            o.copy_from_slice(&q);
        }
        Kind::AxesQuaternion => {
            let axes = inputs[0].row(i);
            let q = pw85::shape::from_axes_quaternion(&axes, &inputs[1].row(i)).map_err(text)?;
            o.copy_from_slice(&representable(&axes, q)?);
        }
        Kind::AxesRotation => {
            let (axes, m): ([f64; 3], [f64; 9]) = (inputs[0].row(i), inputs[1].row(i));
            let rotation = [[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]];
            let q = pw85::shape::from_axes_rotation(&axes, &rotation).map_err(text)?;
            o.copy_from_slice(&representable(&axes, q)?);
        }
        Kind::AxesAngle2d => {
            let axes = inputs[0].row(i);
            let q = pw85::shape::from_axes_angle_2d(&axes, inputs[1].scalar(i)).map_err(text)?;
            o.copy_from_slice(&representable(&axes, q)?);
        }
        Kind::Measure3 => {
            let t = ellipack::measure::pair_term_3d(&inputs[0].row(i));
            measure_row(&t.map_err(|e| e.to_string())?, o);
        }
        Kind::Measure2 => {
            let t = ellipack::measure::pair_term_2d(&inputs[0].row(i));
            measure_row(&t.map_err(|e| e.to_string())?, o);
        }
        // `chunk` hands these to pw85's batch functions; one row gives the same bits.
        Kind::Contact3 => {
            let (r12, q1, q2) = (inputs[0].row(i), inputs[1].row(i), inputs[2].row(i));
            let c = pw85::contact_function::<[f64; 6]>(&r12, &q1, &q2).map_err(text)?;
            o.copy_from_slice(&[c.mu2, c.lambda]);
        }
        Kind::Contact2 => {
            let (r12, q1, q2) = (inputs[0].row(i), inputs[1].row(i), inputs[2].row(i));
            let c = pw85::contact_function::<[f64; 3]>(&r12, &q1, &q2).map_err(text)?;
            o.copy_from_slice(&[c.mu2, c.lambda]);
        }
        Kind::Overlap3 => {
            let (r12, q1, q2) = (inputs[0].row(i), inputs[1].row(i), inputs[2].row(i));
            let v = pw85::overlap::<[f64; 6]>(&r12, &q1, &q2).map_err(text)?;
            o[0] = f64::from(u8::from(v));
        }
        Kind::Overlap2 => {
            let (r12, q1, q2) = (inputs[0].row(i), inputs[1].row(i), inputs[2].row(i));
            let v = pw85::overlap::<[f64; 3]>(&r12, &q1, &q2).map_err(text)?;
            o[0] = f64::from(u8::from(v));
        }
    }
    Ok(())
}

/// The square of the semi-axis `name` = `l` (positive and finite), which must be a finite,
/// normal float64 for the quadratic form to hold the shape: semi-axes from about 1.5e-154 to
/// 1.3e154. Beyond, the form overflows to infinity or underflows to zero.
fn axis_square(name: &str, l: f64) -> Result<f64, String> {
    let l2 = l * l;
    if l2.is_finite() && l2 >= f64::MIN_POSITIVE {
        return Ok(l2);
    }
    let (size, what) = if l2.is_finite() {
        (
            "small",
            "underflows float64 (it loses its digits or becomes 0)",
        )
    } else {
        ("large", "overflows float64")
    };
    Err(format!(
        "{name} = {l:e} is too {size}: its square {what}; a quadratic form holds semi-axes \
         from {:.2e} to {:.2e}",
        f64::MIN_POSITIVE.sqrt(),
        f64::MAX.sqrt()
    ))
}

/// The form `q` of semi-axes `axes` (checked positive and finite by pw85), refused when a
/// semi-axis or the form is beyond float64, naming the semi-axis.
fn representable<const N: usize, const M: usize>(
    axes: &[f64; N],
    q: [f64; M],
) -> Result<[f64; M], String> {
    for (k, &l) in axes.iter().enumerate() {
        axis_square(&format!("axes[{k}]"), l)?;
    }
    if q.iter().all(|x| x.is_finite()) {
        Ok(q)
    } else {
        Err(format!(
            "axes = {axes:?}: the form R diag(axes²) Rᵀ overflows float64; a quadratic form \
             holds semi-axes up to about {:.2e}",
            f64::MAX.sqrt()
        ))
    }
}

/// pypw85's spheroid, Q = a² I + (c² − a²) n nᵀ with `n` as given (a unit vector gives the
/// semi-axes a, a and c) and pypw85's order of operations, every argument checked: a and c
/// positive, finite and representable squared, n finite and non-zero, Q finite and positive
/// definite.
fn spheroid(a: f64, c: f64, n: &[f64; 3]) -> Result<[f64; 6], String> {
    for (index, value) in [a, c].into_iter().enumerate() {
        if !(value.is_finite() && value > 0.0) {
            return Err(pw85::Error::InvalidSemiAxis { index, value }.to_string());
        }
    }
    let (a2, c2) = (axis_square("a", a)?, axis_square("c", c)?);
    if let Some(k) = n.iter().position(|x| !x.is_finite()) {
        return Err(format!("n[{k}] is not finite ({})", n[k]));
    }
    if n.iter().all(|&x| x == 0.0) {
        return Err("n, the axis of revolution, is zero".to_string());
    }
    let [nx, ny, nz] = *n;
    let k = c2 - a2;
    let q = [
        nx * nx * k + a2,
        nx * ny * k,
        nx * nz * k,
        ny * ny * k + a2,
        ny * nz * k,
        nz * nz * k + a2,
    ];
    if q.iter().any(|x| !x.is_finite()) {
        return Err(format!(
            "n = {n:?} is too long: Q = a² I + (c² − a²) n nᵀ overflows float64 (n is used as \
             given, as in pypw85: give a unit vector)"
        ));
    }
    // The eigenvalues are a² (twice) and a² + (c² − a²)|n|² along n, positive unless c < a and
    // |n| > 1.
    let n2 = nx * nx + ny * ny + nz * nz;
    if k < 0.0 && n2 > 1.0 {
        let along_n = c2 * n2 - a2 * (n2 - 1.0);
        if along_n.is_nan() || along_n <= 0.0 {
            return Err(format!(
                "n = {n:?}: with |n|² = {n2} and c < a, Q = a² I + (c² − a²) n nᵀ is not \
                 positive definite (its eigenvalue along n is {along_n:e}); n is used as \
                 given, as in pypw85: give a unit vector"
            ));
        }
    }
    Ok(q)
}

/// The output row of a pair term: U, d², ε, f, X, and whether X is unique (1 or 0).
fn measure_row<const N: usize>(t: &implicit_packing::PairTerm<N>, o: &mut [f64]) {
    o[..4].copy_from_slice(&[t.u, t.d2, t.eps, t.f]);
    o[4..4 + N].copy_from_slice(&t.x);
    o[4 + N] = f64::from(u8::from(t.x_unique));
}

/// The rayon pool of `threads` threads, built once per count.
fn pool(threads: usize) -> PyResult<Arc<rayon::ThreadPool>> {
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> = OnceLock::new();
    let pools = POOLS.get_or_init(Default::default);
    // A poisoned lock only means another call panicked while inserting: the map is still valid.
    let mut pools = pools.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(p) = pools.get(&threads) {
        return Ok(Arc::clone(p));
    }
    let p = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map(Arc::new)
        .map_err(|e| PyValueError::new_err(format!("cannot start {threads} threads: {e}")))?;
    pools.insert(threads, Arc::clone(&p));
    Ok(p)
}

/// Every chunk of `out`, on the calling thread (`threads == 1`), rayon's global pool
/// (`threads == 0`) or `pool`; the error of the lowest failing row.
pub(crate) fn evaluate(
    kind: Kind,
    inputs: &[Input<'_>],
    out: &mut [f64],
    threads: usize,
    pool: Option<&rayon::ThreadPool>,
) -> Result<(), RowError> {
    let step = CHUNK * kind.output_width();
    let job = |buffers: &mut Buffers, (c, o): (usize, &mut [f64])| {
        chunk(kind, inputs, c * CHUNK, o, buffers)
    };
    let parallel = |out: &mut [f64]| {
        out.par_chunks_mut(step)
            .enumerate()
            .map_init(Buffers::default, job)
            .filter_map(Result::err)
            .min_by_key(|e| e.row)
            .map_or(Ok(()), Err)
    };
    if threads == 1 || out.len() <= step {
        let mut buffers = Buffers::default();
        return out
            .chunks_mut(step)
            .enumerate()
            .try_for_each(|c| job(&mut buffers, c));
    }
    match pool {
        Some(pool) => pool.install(|| parallel(out)),
        // Every core: rayon's global pool, the one pw85's own batch functions use.
        None => parallel(out),
    }
}

/// Why the array `name` cannot be read as one slice: not aligned, or not C-contiguous.
fn not_a_slice(name: &str, aligned: bool) -> PyErr {
    PyValueError::new_err(if aligned {
        format!("{name} is not C-contiguous")
    } else {
        format!(
            "{name} is not aligned (its float64 values do not start at a multiple of 8 bytes): \
             np.require(a, requirements='CA') or a copy fixes it"
        )
    })
}

/// `_rows(kind, inputs, out, threads, batch)`: evaluates `kind` on every row.
///
/// Each input is a C-contiguous float64 matrix with the kind's row width and either one row
/// (broadcast) or as many rows as `out`; `out` is C-contiguous float64 with the kind's output
/// width. `threads`: 1 on the calling thread, 0 on every core, n on n threads. `batch` says
/// whether the caller passed rows (the error then names the row).
#[pyfunction]
#[pyo3(signature = (kind, inputs, out, threads, batch))]
pub fn _rows(
    py: Python<'_>,
    kind: &str,
    inputs: Vec<PyReadonlyArray2<'_, f64>>,
    mut out: PyReadwriteArray2<'_, f64>,
    threads: usize,
    batch: bool,
) -> PyResult<()> {
    let kind = Kind::from_name(kind)?;
    let widths = kind.input_widths();
    if inputs.len() != widths.len() {
        return Err(PyValueError::new_err(format!(
            "{} inputs where the kernel takes {}",
            inputs.len(),
            widths.len()
        )));
    }
    let [n, out_width] = [out.shape()[0], out.shape()[1]];
    if out_width != kind.output_width() {
        return Err(PyValueError::new_err(format!(
            "out has rows of {out_width}, not {}",
            kind.output_width()
        )));
    }
    let mut views = Vec::with_capacity(inputs.len());
    for (k, (a, &width)) in inputs.iter().zip(widths).enumerate() {
        let [rows, w] = [a.shape()[0], a.shape()[1]];
        if w != width || !(rows == n || rows == 1) {
            return Err(PyValueError::new_err(format!(
                "input {k} has shape ({rows}, {w}), not (1, {width}) or ({n}, {width})"
            )));
        }
        // `as_slice` also takes a Fortran-ordered matrix, whose rows are not runs of the slice.
        let data = match a.as_slice() {
            Ok(data) if a.is_c_contiguous() => data,
            _ => return Err(not_a_slice(&format!("input {k}"), a.is_aligned())),
        };
        views.push(Input {
            data,
            stride: if rows == 1 { 0 } else { width },
        });
    }
    let (aligned, c_order) = (out.is_aligned(), out.is_c_contiguous());
    let out = match out.as_slice_mut() {
        Ok(out) if c_order => out,
        _ => return Err(not_a_slice("out", aligned)),
    };
    let pool = match threads {
        0 | 1 => None,
        t => pool(t).map(Some)?,
    };
    py.detach(|| evaluate(kind, &views, out, threads, pool.as_deref()))
        .map_err(|e| {
            PyValueError::new_err(if batch {
                format!("row {}: {}", e.row, e.message)
            } else {
                e.message
            })
        })
}

/// `_bench_rust_batch(r12, q1, q2, all_threads)`: the seconds pw85's batch
/// `contact_functions` takes on the pairs of the three (n, 3), (n, 6), (n, 6) matrices, the
/// pairs already laid out as the batch wants them (the building is not timed). The reference
/// for the per-pair cost of the Python call.
#[pyfunction]
pub fn _bench_rust_batch(
    py: Python<'_>,
    r12: PyReadonlyArray2<'_, f64>,
    q1: PyReadonlyArray2<'_, f64>,
    q2: PyReadonlyArray2<'_, f64>,
    all_threads: bool,
) -> PyResult<f64> {
    let slice = |a: &PyReadonlyArray2<'_, f64>, width: usize, name: &str| {
        if a.shape()[1] != width {
            return Err(PyValueError::new_err(format!(
                "{name} must have {width} columns"
            )));
        }
        a.as_slice()
            .map(|s| s.to_vec())
            .map_err(|_| PyValueError::new_err(format!("{name} is not C-contiguous")))
    };
    let (r, a, b) = (
        slice(&r12, 3, "r12")?,
        slice(&q1, 6, "q1")?,
        slice(&q2, 6, "q2")?,
    );
    let n = r.len() / 3;
    if a.len() != 6 * n || b.len() != 6 * n {
        return Err(PyValueError::new_err(
            "r12, q1 and q2 must have the same rows",
        ));
    }
    let pairs: Vec<Pair> = (0..n)
        .map(|i| Pair {
            r12: core::array::from_fn(|k| r[3 * i + k]),
            q1: core::array::from_fn(|k| a[6 * i + k]),
            q2: core::array::from_fn(|k| b[6 * i + k]),
        })
        .collect();
    let parallelism = if all_threads {
        Parallelism::Threads
    } else {
        Parallelism::Serial
    };
    Ok(py.detach(|| {
        let mut out = vec![Ok(pw85::batch::EMPTY_CONTACT); n];
        let start = std::time::Instant::now();
        contact_functions(&pairs, &mut out, parallelism);
        let seconds = start.elapsed().as_secs_f64();
        std::hint::black_box(&out);
        seconds
    }))
}
