//! The packer from Python: scenes (TOML text, a file, or a dict read as the table of values a
//! scene file parses to), the run with the GIL released while the calling thread relays
//! progress and polls Python's signals, the packing object, reading a packing folder and
//! verifying a packing.

use ellipack::folder::{HISTORY_FILE, Published, Staging};
use ellipack::pack::{MultiStartProgress, Observer, RunOptions, run, time_limit_of};
use ellipack::packing::{Container, Item, Items, Packing, Summary};
use ellipack::scene::{Overrides, Scene};
use numpy::{PyArray1, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{
    PyFileNotFoundError, PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyTypeError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// How often the calling thread wakes to run Python's signal handlers during a run.
const SIGNAL_POLL: Duration = Duration::from_millis(100);

fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

pyo3::create_exception!(
    ellipack,
    NotReached,
    PyValueError,
    "A container of fixed size (its size or `packing_fraction` given) that the run did not fill \
     without overlap before its time limit (or before Ctrl-C). A ValueError, so code that \
     catches ValueError still does. Its `packing` attribute is the least overlapping \
     configuration, a Packing that is not a packing: items may overlap or stick out, \
     `packing.certificate` counts them and `packing.summary['not_reached']` is True (what \
     `ellipack pack` writes to OUT/unfinished/)."
);

/// The scene of a dict (nested dicts, lists, tuples, str, bool, int, float; NumPy arrays and
/// scalars through their `tolist()`) as the table of values a scene file parses to, checked as
/// a scene file is ([`Scene::from_table`]).
fn scene_of_dict(obj: &Bound<'_, PyAny>) -> PyResult<Scene> {
    match toml_value(obj, "scene")? {
        toml::Value::Table(t) => Scene::from_table(&t, "<scene>").map_err(value_error),
        _ => Err(PyTypeError::new_err("a scene is a dict (its TOML tables)")),
    }
}

fn toml_value(obj: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    if obj.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(obj.extract()?));
    }
    if obj.is_instance_of::<PyInt>() {
        // The seed goes up to 2⁶⁴ − 1, beyond TOML's integers: the scene takes it as a string.
        return Ok(match obj.extract::<i64>() {
            Ok(i) => toml::Value::Integer(i),
            Err(_) => toml::Value::String(obj.str()?.to_string()),
        });
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(obj.extract()?));
    }
    if obj.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(obj.extract()?));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in d.iter() {
            let name: String = k.extract().map_err(|_| {
                PyTypeError::new_err(format!("{key}: the keys of a table are str, not {k:?}"))
            })?;
            let value = toml_value(&v, &format!("{key}.{name}"))?;
            table.insert(name, value);
        }
        return Ok(toml::Value::Table(table));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, v) in obj.try_iter()?.enumerate() {
            items.push(toml_value(&v?, &format!("{key}[{i}]"))?);
        }
        return Ok(toml::Value::Array(items));
    }
    if obj.hasattr("tolist")? {
        return toml_value(&obj.call_method0("tolist")?, key);
    }
    Err(PyTypeError::new_err(format!(
        "{key}: {} has no TOML form (use dict, list, str, bool, int or float)",
        obj.get_type().name()?
    )))
}

/// A packing: container and items, with the summary of the run (or of the folder) that made it.
#[pyclass(name = "Packing", module = "ellipack", frozen)]
pub struct PyPacking {
    packing: Packing,
    summary: Summary,
    history: Option<String>,
    interrupted: bool,
}

impl PyPacking {
    /// A packing that no run of this process made: it has no history.
    fn without_run(packing: Packing, summary: Summary) -> Self {
        PyPacking {
            packing,
            summary,
            history: None,
            interrupted: false,
        }
    }

    /// One row per item, as `ellipse` or `ellipsoid` reads it.
    fn item_rows<'py>(
        &self,
        py: Python<'py>,
        ellipse: impl Fn(&Item<2>) -> Vec<f64>,
        ellipsoid: impl Fn(&Item<3>) -> Vec<f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows: Vec<Vec<f64>> = match self.packing.items() {
            Items::Ellipses(v) => v.iter().map(ellipse).collect(),
            Items::Ellipsoids(v) => v.iter().map(ellipsoid).collect(),
        };
        PyArray2::from_vec2(py, &rows).map_err(value_error)
    }

    fn json(py: Python<'_>, text: &str) -> PyResult<Py<PyAny>> {
        Ok(py.import("json")?.call_method1("loads", (text,))?.unbind())
    }
}

#[pymethods]
impl PyPacking {
    /// 2 (ellipses) or 3 (ellipsoids).
    #[getter]
    fn dimension(&self) -> usize {
        self.packing.items().dimension()
    }

    fn __len__(&self) -> usize {
        self.packing.items().len()
    }

    /// The centres, shape (m, dimension).
    #[getter]
    fn centres<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.item_rows(py, |e| e.centre.to_vec(), |e| e.centre.to_vec())
    }

    /// The semi-axes, shape (m, dimension): semi-axis k lies along column k of the rotation.
    #[getter]
    fn semi_axes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.item_rows(py, |e| e.semi_axes.to_vec(), |e| e.semi_axes.to_vec())
    }

    /// 3D: the unit quaternions (w, x, y, z), shape (m, 4), Hamilton active rotations; 2D: None.
    #[getter]
    fn quaternions<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        match self.packing.items() {
            Items::Ellipses(_) => Ok(None),
            Items::Ellipsoids(v) => {
                let rows: Vec<Vec<f64>> = v.iter().map(|e| e.quaternion().to_vec()).collect();
                PyArray2::from_vec2(py, &rows)
                    .map(Some)
                    .map_err(value_error)
            }
        }
    }

    /// 2D: the angles θ (radians), shape (m,); 3D: None.
    #[getter]
    fn angles<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        match self.packing.items() {
            Items::Ellipses(v) => Some(PyArray1::from_iter(py, v.iter().map(|e| e.theta()))),
            Items::Ellipsoids(_) => None,
        }
    }

    /// The container as in summary.json: `kind`, `center` and its size (`radius`,
    /// `semi_axes` or `half_sides`).
    #[getter]
    fn container(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let text = serde_json::to_string(self.packing.container()).map_err(value_error)?;
        Self::json(py, &text)
    }

    /// Total item area or volume over the container's.
    #[getter]
    fn density(&self) -> f64 {
        self.packing.density()
    }

    /// The certificate: `overlapping_pairs`, `containment_violations` (both 0 for a certified
    /// packing) and `min_mu2`, the smallest PW85 μ² over the pairs whose enclosing balls meet.
    #[getter]
    fn certificate(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let text = serde_json::to_string(&self.summary.certificate).map_err(value_error)?;
        Self::json(py, &text)
    }

    /// The whole of summary.json as a dict.
    #[getter]
    fn summary(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let text = ellipack::summary_json::summary_json(&self.summary).map_err(value_error)?;
        Self::json(py, &text)
    }

    /// True when the run was stopped by Ctrl-C (or by the progress callback raising
    /// KeyboardInterrupt) before its time limit: the packing is the best certified one found.
    #[getter]
    fn interrupted(&self) -> bool {
        self.interrupted
    }

    /// history.csv of the run (one row per local minimisation), None for a packing read from
    /// a folder.
    #[getter]
    fn history(&self) -> Option<String> {
        self.history.clone()
    }

    /// Writes packing.csv, summary.json, packing.xyz (when `xyz`) and the run's history.csv
    /// into `folder` (created with its parents if needed), as one set: the previous files of the folder are
    /// replaced together or not at all.
    #[pyo3(signature = (folder, xyz = true))]
    fn write(&self, py: Python<'_>, folder: PathBuf, xyz: bool) -> PyResult<()> {
        py.detach(|| -> Result<(), String> {
            ellipack::pack::probe_output_folder(&folder).map_err(|e| e.to_string())?;
            let staging = Staging::begin(&folder).map_err(|e| e.to_string())?;
            let staged = staging.path();
            ellipack::folder::write_files(staged, &self.packing, &self.summary, xyz)
                .map_err(|e| e.to_string())?;
            if let Some(history) = &self.history {
                ellipack::write_atomically(&staged.join(HISTORY_FILE), history.as_bytes())
                    .map_err(|e| e.to_string())?;
            }
            match staging.commit().map_err(|e| e.to_string())? {
                Published::Swapped | Published::InPlace(_) => Ok(()),
            }
        })
        .map_err(PyOSError::new_err)
    }

    fn __repr__(&self) -> String {
        let c = &self.summary.certificate;
        format!(
            "<ellipack.Packing: {} {} in a {}, density {:.5}, {} overlapping pairs, {} items \
             outside{}>",
            self.packing.items().len(),
            self.packing.items().noun(),
            self.packing.container().kind(),
            self.packing.density(),
            c.overlapping_pairs,
            c.containment_violations,
            if self.interrupted {
                ", interrupted"
            } else {
                ""
            }
        )
    }
}

/// The observer of a run in the worker thread: finished local minimisations go to the calling
/// thread through a channel, the stop request comes from it through a flag.
struct Relay<'a> {
    progress: mpsc::Sender<MultiStartProgress>,
    stop: &'a AtomicBool,
}

impl Observer for Relay<'_> {
    fn finished(&mut self, p: &MultiStartProgress) {
        // The calling thread has stopped listening only when it is about to return.
        let _ = self.progress.send(*p);
    }

    fn should_stop(&self) -> bool {
        self.stop.load(Ordering::SeqCst)
    }
}

/// `_pack(scene, path, time_limit, seed, threads, progress)`: packs `scene` (TOML text or a
/// dict) or the scene of the file `path` (the built-in scene when both are None) and returns
/// the packing.
///
/// The run happens on a worker thread with the GIL released. The calling thread wakes every
/// 100 ms to run Python's signal handlers and calls `progress(dict)` after every local
/// minimisation. KeyboardInterrupt (Ctrl-C, or raised by `progress`) stops the run, which
/// returns its best certified packing with `interrupted` set; any other exception from a
/// signal handler or from `progress` stops the run and is raised once it has stopped.
#[pyfunction]
#[pyo3(signature = (scene, path, time_limit, seed, threads, progress))]
pub fn _pack(
    py: Python<'_>,
    scene: Option<Bound<'_, PyAny>>,
    path: Option<PathBuf>,
    time_limit: Option<f64>,
    seed: Option<u64>,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<PyPacking> {
    let scene = match (scene, path) {
        (Some(text), _) if text.is_instance_of::<PyString>() => {
            Scene::from_toml_str(&text.extract::<String>()?, "<scene>").map_err(value_error)?
        }
        (Some(dict), _) => scene_of_dict(&dict)?,
        (None, Some(path)) => Scene::from_file(&path).map_err(value_error)?,
        (None, None) => Scene::default_scene(),
    };
    let scene = scene.overridden(&Overrides {
        time_limit: time_limit
            .map(time_limit_of)
            .transpose()
            .map_err(value_error)?,
        seed,
        threads,
    });
    let options = RunOptions::default();
    let stop = AtomicBool::new(false);
    let (sender, receiver) = mpsc::channel();
    let relay = Relay {
        progress: sender,
        stop: &stop,
    };
    let mut interrupted = false;
    let mut pending: Option<PyErr> = None;
    let result = std::thread::scope(|s| {
        let (scene, options) = (&scene, &options);
        let worker = s.spawn(move || {
            let mut relay = relay;
            run(scene, options, &mut relay)
        });
        let mut receiver = receiver;
        let mut stop_with = |e: PyErr, py: Python<'_>| {
            if e.is_instance_of::<PyKeyboardInterrupt>(py) {
                interrupted = true;
            } else if pending.is_none() {
                pending = Some(e);
            }
            stop.store(true, Ordering::SeqCst);
        };
        loop {
            let (message, r) = py.detach(move || (receiver.recv_timeout(SIGNAL_POLL), receiver));
            receiver = r;
            match message {
                Ok(p) => {
                    if let Some(callback) = &progress {
                        let report = progress_dict(py, &p);
                        if let Err(e) = report.and_then(|d| callback.call1(py, (d,))) {
                            stop_with(e, py);
                        }
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
            if let Err(e) = py.check_signals() {
                stop_with(e, py);
            }
        }
        let joined = worker.join();
        // A Ctrl-C that came after the last poll would otherwise be raised by the next Python
        // statement and lose the packing.
        if let Err(e) = py.check_signals() {
            stop_with(e, py);
        }
        joined
    })
    .map_err(|_| PyRuntimeError::new_err("the packing run panicked"))?;
    if let Some(e) = pending {
        return Err(e);
    }
    let outcome = match result {
        Ok(outcome) => outcome,
        Err(e) => return Err(pack_error(py, e, interrupted)),
    };
    Ok(PyPacking {
        packing: outcome.packing,
        summary: outcome.summary,
        history: Some(outcome.history.into_text()),
        interrupted: interrupted || outcome.interrupted,
    })
}

/// The exception of a run that failed: [`NotReached`] with the least overlapping
/// configuration as its `packing` for a fixed container that was not filled, ValueError
/// otherwise.
fn pack_error(py: Python<'_>, e: ellipack::Error, interrupted: bool) -> PyErr {
    let message = e.to_string();
    let ellipack::Error::NotReached(unfinished) = e else {
        return value_error(message);
    };
    let stopped = interrupted || unfinished.interrupted;
    let err = NotReached::new_err(format!(
        "{message}{}; that configuration, which is not a packing, is this exception's \
         `packing`",
        if stopped { " (stopped by Ctrl-C)" } else { "" }
    ));
    let packing = PyPacking {
        packing: unfinished.packing,
        summary: unfinished.summary,
        history: Some(unfinished.history.into_text()),
        interrupted: stopped,
    };
    match Py::new(py, packing).and_then(|p| err.value(py).setattr("packing", p)) {
        Ok(()) => err,
        Err(e) => e,
    }
}

fn progress_dict<'py>(py: Python<'py>, p: &MultiStartProgress) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("local_minimisations", p.local_minimisations)?;
    d.set_item("best_density", p.best_density)?;
    d.set_item("last_density", p.last_density)?;
    d.set_item("elapsed", p.elapsed.as_secs_f64())?;
    Ok(d)
}

/// `read_packing(folder)`: the packing of a folder written by `ellipack pack` or
/// `Packing.write` (packing.csv and summary.json).
#[pyfunction]
pub fn read_packing(py: Python<'_>, folder: PathBuf) -> PyResult<PyPacking> {
    let (packing, summary) = py
        .detach(|| ellipack::folder::read_packing_dir(&folder))
        .map_err(|e| match &e {
            // A file that cannot be read is an OSError, as Python's own `open` raises.
            ellipack::Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
                PyFileNotFoundError::new_err(e.to_string())
            }
            ellipack::Error::Io { .. } => PyOSError::new_err(e.to_string()),
            _ => value_error(e),
        })?;
    Ok(PyPacking::without_run(packing, summary))
}

/// The container of summary.json's form (JSON text), with a message naming `container`.
fn container_of(container_json: &str) -> PyResult<Container> {
    serde_json::from_str(container_json)
        .map_err(|e| PyValueError::new_err(format!("container: {e}")))
}

/// `_container_dimension(container_json)`: 2 or 3, the dimension of the items the container
/// holds, so that the arrays of `packing_from_arrays` are checked before they are converted.
#[pyfunction]
pub fn _container_dimension(container_json: &str) -> PyResult<usize> {
    Ok(container_of(container_json)?.dimension())
}

/// The rows of the C-contiguous float64 matrix `name`, which must have `width` columns.
fn matrix_rows<'a>(
    name: &str,
    a: &'a PyReadonlyArray2<'_, f64>,
    width: usize,
) -> PyResult<std::slice::ChunksExact<'a, f64>> {
    let columns = a.shape()[1];
    if columns != width {
        return Err(PyValueError::new_err(format!(
            "{name} has {columns} columns, not {width}"
        )));
    }
    // `as_slice` also takes a Fortran-ordered matrix, whose rows are not runs of the slice.
    let data = match a.as_slice() {
        Ok(data) if a.is_c_contiguous() => data,
        _ => {
            return Err(PyValueError::new_err(format!(
                "{name} is not an aligned C-contiguous array"
            )));
        }
    };
    // `width`: 1 to 4, never 0, which `chunks_exact` refuses.
    Ok(data.chunks_exact(width.max(1)))
}

/// `_packing_from_arrays(container_json, centres, semi_axes, orientations)`: a packing of
/// items given as C-contiguous float64 matrices of m rows (centres and semi-axes of `dim`
/// columns; orientations: quaternions (w, x, y, z), 4 columns, in 3D, angles, 1 column, in
/// 2D), read in place, checked, with its certificate computed.
#[pyfunction]
pub fn _packing_from_arrays(
    py: Python<'_>,
    container_json: &str,
    centres: PyReadonlyArray2<'_, f64>,
    semi_axes: PyReadonlyArray2<'_, f64>,
    orientations: PyReadonlyArray2<'_, f64>,
) -> PyResult<PyPacking> {
    let container = container_of(container_json)?;
    let m = centres.shape()[0];
    if semi_axes.shape()[0] != m || orientations.shape()[0] != m {
        return Err(PyValueError::new_err(format!(
            "{m} centres, {} semi-axes and {} orientations: one of each per item",
            semi_axes.shape()[0],
            orientations.shape()[0]
        )));
    }
    if m > ellipack::scene::MAX_ITEMS {
        return Err(PyValueError::new_err(format!(
            "{m} items, more than {}",
            ellipack::scene::MAX_ITEMS
        )));
    }
    let dim = container.dimension();
    let c = matrix_rows("centres", &centres, dim)?;
    let a = matrix_rows("semi_axes", &semi_axes, dim)?;
    let rows = c.zip(a);
    let items = if dim == 2 {
        let o = matrix_rows("orientations", &orientations, 1)?;
        Items::Ellipses(
            rows.zip(o)
                .map(|((c, a), o)| Item::ellipse([c[0], c[1]], [a[0], a[1]], o[0]))
                .collect(),
        )
    } else {
        let o = matrix_rows("orientations", &orientations, 4)?;
        Items::Ellipsoids(
            rows.zip(o)
                .map(|((c, a), q)| {
                    Item::ellipsoid(
                        [c[0], c[1], c[2]],
                        [a[0], a[1], a[2]],
                        [q[0], q[1], q[2], q[3]],
                    )
                })
                .collect(),
        )
    };
    let packing = Packing::new(container, items).map_err(value_error)?;
    let certificate = py
        .detach(|| ellipack::pack::verify(&packing))
        .map_err(value_error)?;
    let summary = Summary::new(&packing, packing.container().measure(), 0.0, 0, certificate);
    Ok(PyPacking::without_run(packing, summary))
}

/// `verify(packing)`: the packing checked again from its items, independently of how it was
/// made (PW85 verdicts on every pair whose enclosing balls meet, exact containment). Returns
/// a dict: `certified`, `overlapping_pairs` (a list of (i, j, μ²), deepest first), `outside`
/// (a list of (i, t): the container scaled by t about its centre would hold item i), and
/// `min_mu2`.
#[pyfunction]
pub fn verify<'py>(
    py: Python<'py>,
    packing: &Bound<'py, PyPacking>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = packing.get();
    let v = py
        .detach(|| ellipack::pack::verify_detailed(&p.packing))
        .map_err(value_error)?;
    let d = PyDict::new(py);
    d.set_item("certified", v.certificate.is_certified())?;
    let pairs: Vec<(usize, usize, f64)> = v
        .overlapping_pairs
        .iter()
        .map(|o| (o.items.0, o.items.1, o.mu2))
        .collect();
    d.set_item("overlapping_pairs", pairs)?;
    let outside: Vec<(usize, f64)> = v.outside.iter().map(|o| (o.item, o.scale)).collect();
    d.set_item("outside", outside)?;
    d.set_item("min_mu2", v.certificate.min_mu2)?;
    Ok(d)
}

/// `_analyse(packing, gap, bond_cutoff, rdf_range, rdf_bins)`: the structure of a packing
/// ([`ellipack::analysis`]) as the text of structure.json, and g(r) as two lists.
#[pyfunction]
#[pyo3(signature = (packing, gap, bond_cutoff, rdf_range, rdf_bins))]
pub fn _analyse(
    py: Python<'_>,
    packing: &Bound<'_, PyPacking>,
    gap: f64,
    bond_cutoff: Option<f64>,
    rdf_range: Option<f64>,
    rdf_bins: usize,
) -> PyResult<(String, Vec<f64>, Vec<f64>)> {
    let p = packing.get();
    let settings = ellipack::analysis::settings(gap, p.summary.repair_dilation())
        .with_bond_cutoff(bond_cutoff)
        .with_rdf_range(rdf_range)
        .with_rdf_bins(rdf_bins);
    let s = py
        .detach(|| ellipack::analysis::analyse(&p.packing, &settings))
        .map_err(value_error)?;
    Ok((
        ellipack::analysis::structure_json(&s),
        s.rdf.r.clone(),
        s.rdf.g.clone(),
    ))
}
