//! The learned observer's network (docs/method.md section 5): `train`, `Network` (`grow`,
//! `predict`, `save`) and `load_network`, as `admittance train` / `admittance grow` do it
//! (crates/cli/src/train_cmd.rs): free-motion data from a CSV file or a dict of arrays,
//! inputs `[q, qdot, qddot]` through the optional input conditioning, the ridge parameter
//! chosen on a separate validation set when given, else by blocked cross-validation over
//! `folds` contiguous stretches of the rows (issue #22: never the tail of the same
//! motion; `validation_fraction`, the last rows held out, is kept for compatibility). The GIL is released while files are read
//! and while the network is fitted, grown or evaluated.

use std::path::PathBuf;
use std::sync::Arc;

use admittance_dynamics::Identification;
use admittance_learning::broad::{
    fit, BroadConfig, BroadModel, Dataset, FrictionFeatures, GrowthSpec, ValidationSplit, WidthRule,
};
use numpy::PyArray1;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::convert::{broad_error, matrix_out, rows, value_error, vector_out};
use crate::free_motion::{data_arg, training_arrays};
use crate::model::PyModel;

/// Which rows validated a fit (and so which rows trained it).
#[derive(Clone, Copy)]
enum Holdout {
    /// The last fraction of the rows (compatibility).
    Fraction(f64),
    /// A separate validation set: every data row trained.
    Separate,
    /// Blocked cross-validation: every data row trained.
    CrossValidation,
}

impl Holdout {
    /// How a loaded network was validated: as its file records it, else by
    /// cross-validation (the default of `train` and `admittance train`).
    fn recorded(model: &BroadModel) -> Holdout {
        match model.provenance().data.map(|d| d.validation) {
            Some(ValidationSplit::TrailingFraction { fraction }) => Holdout::Fraction(fraction),
            Some(ValidationSplit::SeparateData) => Holdout::Separate,
            _ => Holdout::CrossValidation,
        }
    }
}

/// How a network was trained, so that `grow` can rebuild the same training rows.
#[derive(Clone)]
struct TrainOptions {
    holdout: Holdout,
    input_filter_hz: f64,
    nominal: Option<Arc<Identification>>,
    joints: Vec<String>,
}

fn check_fraction(f: f64) -> PyResult<f64> {
    if f > 0.0 && f < 1.0 {
        Ok(f)
    } else {
        Err(value_error(format!(
            "`validation_fraction` is {f}, must be in (0, 1)"
        )))
    }
}

/// Training and validation rows: a split of `data` at `1 - fraction`, all of `data` and
/// the separate `validation` set, or all of `data` alone (cross-validation).
struct Split {
    x: Vec<f64>,
    y: Vec<f64>,
    validation: Option<(Vec<f64>, Vec<f64>)>,
}

impl Split {
    fn new(
        (x, y, rows_n): (Vec<f64>, Vec<f64>, usize),
        validation: Option<(Vec<f64>, Vec<f64>, usize)>,
        holdout: Holdout,
        n: usize,
    ) -> PyResult<Self> {
        match (validation, holdout) {
            (Some((xv, yv, _)), _) => Ok(Split {
                x,
                y,
                validation: Some((xv, yv)),
            }),
            (None, Holdout::CrossValidation) => Ok(Split {
                x,
                y,
                validation: None,
            }),
            (None, Holdout::Fraction(f)) => {
                let train_rows = ((rows_n as f64) * (1.0 - f)).floor() as usize;
                if train_rows < 2 || train_rows >= rows_n {
                    return Err(value_error(format!(
                        "{rows_n} rows are too few to hold out a validation fraction of {f}"
                    )));
                }
                let (x, xv) = (x[..train_rows * 3 * n].to_vec(), x[train_rows * 3 * n..].to_vec());
                let (y, yv) = (y[..train_rows * n].to_vec(), y[train_rows * n..].to_vec());
                Ok(Split {
                    x,
                    y,
                    validation: Some((xv, yv)),
                })
            }
            (None, Holdout::Separate) => Err(value_error(
                "this network was trained with a separate validation set: pass `validation=` (the same data) to grow it",
            )),
        }
    }

    fn sets(&self, n: usize) -> PyResult<(Dataset<'_>, Option<Dataset<'_>>)> {
        let train = Dataset::new(&self.x, &self.y, 3 * n, n).map_err(broad_error)?;
        let val = match &self.validation {
            Some((xv, yv)) => Some(Dataset::new(xv, yv, 3 * n, n).map_err(broad_error)?),
            None => None,
        };
        Ok((train, val))
    }
}

fn require_finite_metrics(nrmse: &[f64], what: &str) -> PyResult<()> {
    if nrmse.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(PyRuntimeError::new_err(format!(
            "{what} failed: the validation NRMSE is not finite ({nrmse:?})"
        )))
    }
}

/// A trained flat RBF network of the learned (or hybrid) observer: inputs `[q, qdot,
/// qddot]`, outputs one torque per joint. From `train` or `load_network`.
#[pyclass(module = "admittance._admittance", name = "Network")]
pub struct PyNetwork {
    pub(crate) model: BroadModel,
    validation_nrmse: Option<Vec<f64>>,
    samples: Option<usize>,
    validation_samples: Option<usize>,
    seconds: Option<f64>,
    options: Option<TrainOptions>,
}

impl PyNetwork {
    fn joints(&self) -> usize {
        self.model.d_out()
    }

    /// A copy for an observer, without the growth state (the Gram matrix and its factor).
    pub(crate) fn deployment_copy(&self) -> BroadModel {
        let mut m = self.model.clone();
        m.strip_growth_state();
        m
    }
}

/// Fits the learned observer's network to free-motion data (what `admittance train` does).
///
/// `data`: the path of a free-motion CSV file (columns `t`, `q.JOINT`, `qdot.JOINT`,
/// `qddot.JOINT`, `tau.JOINT`; docs/outputs.md) or a dict with `t` `(N,)` and `q`, `qdot`,
/// `qddot`, `tau` as `(N, n)` arrays in the chain order of `m` (or the CSV column names as
/// `(N,)` arrays). `nodes`: Gaussian enhancement nodes. `friction_features`: add
/// `tanh(qdot / v)` inputs (`friction_scales` v, default 0.01, 0.05, 0.2 rad/s).
/// `input_filter_hz`: the observers' second input filter (0: the columns as recorded; the
/// observer must then be fed through `InputConditioner` with the same cut-off); default the
/// nominal identification's when it records one, else 0.
/// The ridge parameter is chosen, and the validation NRMSE measured, on `validation`, a
/// separate data set (a different excitation), when given; else by blocked
/// cross-validation over `folds` contiguous stretches of `data` (each scored by a fit on
/// the others). Either way every row of `data` trains. `validation_fraction`: hold out
/// the last rows instead (the tail of the same motion; kept for compatibility). `nominal`: train the
/// hybrid observer's residual `tau - RNEA_nominal(q, qdot, qddot)` instead of `tau`.
/// `seed`, `width_scale`, `width_neighbours`: centre placement and widths (the scenario
/// files' `[observer.training]` keys). The GIL is released while it reads and fits.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (data, m, nodes=admittance_learning::broad::DEFAULT_NODES, *, friction_features=false, friction_scales=None,
    input_filter_hz=None, validation_fraction=None, validation=None, folds=5, seed=None,
    width_scale=2.0, width_neighbours=8, nominal=None))]
pub fn train(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    m: &Bound<'_, PyModel>,
    nodes: usize,
    friction_features: bool,
    friction_scales: Option<Vec<f64>>,
    input_filter_hz: Option<f64>,
    validation_fraction: Option<f64>,
    validation: Option<&Bound<'_, PyAny>>,
    folds: usize,
    seed: Option<u64>,
    width_scale: f64,
    width_neighbours: usize,
    nominal: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyNetwork> {
    let model = m.get().model.clone();
    let n = model.nq();
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let validation = validation.filter(|v| !v.is_none());
    let holdout = match (validation, validation_fraction) {
        (Some(_), Some(_)) => {
            return Err(value_error(
                "give `validation` or `validation_fraction`, not both",
            ))
        }
        (Some(_), None) => Holdout::Separate,
        (None, Some(f)) => Holdout::Fraction(check_fraction(f)?),
        (None, None) => Holdout::CrossValidation,
    };
    if nodes == 0 {
        return Err(value_error(
            "`nodes` is 0, must be a positive integer (Gaussian enhancement nodes, e.g. 1000)",
        ));
    }
    if folds < 2 {
        return Err(value_error(format!(
            "`folds` is {folds}, must be >= 2 (contiguous stretches of the rows)"
        )));
    }
    if friction_scales.is_some() && !friction_features {
        return Err(value_error(
            "`friction_scales` needs `friction_features=True`",
        ));
    }
    let nominal = match nominal.filter(|v| !v.is_none()) {
        Some(nm) => {
            let nm = crate::identification::nominal_arg(nm, "nominal")?;
            if nm.model.joint_names().ne(model.joint_names()) {
                return Err(value_error(
                    "`nominal` must have the joints of `m`, in the same order",
                ));
            }
            Some(nm)
        }
        None => None,
    };
    let input_filter_hz = nominal_filter_hz(input_filter_hz, nominal.as_deref())?;
    let train_arg = data_arg(data, "data", n, Some(&joints))?;
    let val_arg = validation
        .map(|v| data_arg(v, "validation", n, Some(&joints)))
        .transpose()?;
    let defaults = BroadConfig::default();
    let config = BroadConfig {
        nodes,
        friction: FrictionFeatures::for_observer(n, friction_features, friction_scales),
        seed: seed.unwrap_or(defaults.seed),
        cv_folds: folds,
        widths: WidthRule::Knn {
            k: width_neighbours,
            scale: width_scale,
        },
        // A residual on a nominal model keeps the model alone where it does not pay;
        // without a recording of other motion nothing shows that it pays (issue 30).
        zero_unhelpful_outputs: nominal.is_some(),
        zero_all_outputs: nominal.is_some() && validation.is_none(),
        ..defaults
    };
    if config.zero_all_outputs {
        let message = c"`nominal` without `validation`: cross-validation over one recording is \
            not evidence that a residual pays on new motion, so every output is zero (the hybrid \
            observer is the momentum observer on the nominal model); pass another recording as \
            `validation=` to fit one";
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            message,
            1,
        )?;
    }
    let options = TrainOptions {
        holdout,
        input_filter_hz,
        nominal: nominal.clone(),
        joints: joints.clone(),
    };
    py.detach(move || {
        let nominal = nominal.as_deref();
        let train_rows = training_arrays(
            train_arg,
            "data",
            n,
            Some(&joints),
            input_filter_hz,
            nominal,
        )?;
        let val_rows = val_arg
            .map(|v| training_arrays(v, "validation", n, Some(&joints), input_filter_hz, nominal))
            .transpose()?;
        let repeats = match (&val_rows, holdout) {
            (None, Holdout::CrossValidation) => {
                crate::free_motion::repeat_period_of_rows(&train_rows.0, n, folds)
            }
            _ => None,
        };
        let split = Split::new(train_rows, val_rows, holdout, n)?;
        let (train_set, val_set) = split.sets(n)?;
        let (net, report) = fit(&train_set, val_set.as_ref(), &config).map_err(broad_error)?;
        require_finite_metrics(&report.validation_nrmse, "training")?;
        let network = PyNetwork {
            model: net,
            validation_nrmse: Some(report.validation_nrmse),
            samples: Some(report.samples),
            validation_samples: Some(report.validation_samples),
            seconds: Some(report.times.total_s),
            options: Some(options),
        };
        Ok((network, repeats))
    })
    .and_then(|(network, repeats)| {
        if let Some(period) = repeats {
            crate::free_motion::warn_repeating(py, "data", period)?;
        }
        Ok(network)
    })
}

/// The conditioning of a residual: the identification's (`summary.input_filter_hz`, when it
/// records one), which `given` must equal; else `given` or 0 (issue 30: settings travel).
fn nominal_filter_hz(given: Option<f64>, nominal: Option<&Identification>) -> PyResult<f64> {
    let recorded = nominal
        .map(|i| i.summary.input_filter_hz)
        .filter(|hz| *hz > 0.0);
    match (given, recorded) {
        (Some(g), Some(r)) if g.to_bits() != r.to_bits() => Err(value_error(format!(
            "`input_filter_hz` is {g}, but `nominal` was fitted on signals conditioned at {r} Hz: \
             leave it out (the identification's is used)"
        ))),
        (_, Some(r)) => Ok(r),
        (g, None) => Ok(g.unwrap_or(0.0)),
    }
}

/// Loads a network written by `Network.save` or `admittance train` (versioned,
/// checksummed). Its validation NRMSE and training settings are not stored in the file:
/// those attributes are `None`, and `grow` takes the CLI's defaults.
#[pyfunction]
pub fn load_network(py: Python<'_>, path: PathBuf) -> PyResult<PyNetwork> {
    let model = py.detach(|| BroadModel::load(&path)).map_err(broad_error)?;
    Ok(PyNetwork {
        samples: model.training_samples(),
        model,
        validation_nrmse: None,
        validation_samples: None,
        seconds: None,
        options: None,
    })
}

#[pymethods]
impl PyNetwork {
    /// Adds `nodes` Gaussian nodes without retraining (what `admittance grow` does; equal to
    /// a retrain on the grown node set): `data` must be the data the network was trained
    /// on, formed the same way. The options default to how this network was trained
    /// (`validation_fraction`, `input_filter_hz`, `nominal`; for a loaded network the
    /// validation its file records, else cross-validation, no filter and no nominal
    /// model); a network trained with a separate `validation` set needs it again. Updates
    /// `nodes` and `validation_nrmse` (`None` after a growth under cross-validation: no
    /// rows are held out and lambda is kept). The GIL is released meanwhile.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (nodes, data, *, validation=None, validation_fraction=None,
        input_filter_hz=None, nominal=None, seed=1))]
    fn grow(
        &mut self,
        py: Python<'_>,
        nodes: usize,
        data: &Bound<'_, PyAny>,
        validation: Option<&Bound<'_, PyAny>>,
        validation_fraction: Option<f64>,
        input_filter_hz: Option<f64>,
        nominal: Option<&Bound<'_, PyAny>>,
        seed: u64,
    ) -> PyResult<()> {
        let n = self.joints();
        let trained = self.options.clone();
        let joints = trained.as_ref().map(|o| o.joints.clone());
        let validation = validation.filter(|v| !v.is_none());
        let holdout = match (validation, validation_fraction) {
            (Some(_), Some(_)) => {
                return Err(value_error(
                    "give `validation` or `validation_fraction`, not both",
                ))
            }
            (Some(_), None) => Holdout::Separate,
            (None, Some(f)) => Holdout::Fraction(check_fraction(f)?),
            (None, None) => match &trained {
                Some(o) => o.holdout,
                None => Holdout::recorded(&self.model),
            },
        };
        let filter = input_filter_hz.unwrap_or(trained.as_ref().map_or(0.0, |o| o.input_filter_hz));
        let nominal = match nominal.filter(|v| !v.is_none()) {
            Some(nm) => Some(crate::identification::nominal_arg(nm, "nominal")?),
            None => trained.as_ref().and_then(|o| o.nominal.clone()),
        };
        let train_arg = data_arg(data, "data", n, joints.as_deref())?;
        let val_arg = validation
            .map(|v| data_arg(v, "validation", n, joints.as_deref()))
            .transpose()?;
        let config = BroadConfig {
            friction: self.model.friction().clone(),
            ..BroadConfig::default()
        };
        let net = &mut self.model;
        let (nrmse, seconds) = py.detach(|| -> PyResult<(Option<Vec<f64>>, f64)> {
            let nominal = nominal.as_deref();
            let rows_t = training_arrays(train_arg, "data", n, joints.as_deref(), filter, nominal)?;
            let rows_v = val_arg
                .map(|v| training_arrays(v, "validation", n, joints.as_deref(), filter, nominal))
                .transpose()?;
            let split = Split::new(rows_t, rows_v, holdout, n)?;
            let (train_set, val_set) = split.sets(n)?;
            let report = net
                .grow(
                    &train_set,
                    &GrowthSpec::KMeansPlusPlus { count: nodes, seed },
                    &config,
                )
                .map_err(broad_error)?;
            let nrmse = match &val_set {
                Some(v) => {
                    let e = net.evaluate(v, 0).map_err(broad_error)?;
                    require_finite_metrics(&e, "growth")?;
                    Some(e)
                }
                None => None,
            };
            Ok((nrmse, report.total_s))
        })?;
        self.validation_nrmse = nrmse;
        self.seconds = Some(seconds);
        Ok(())
    }

    /// The network's output for inputs `q`, `qdot`, `qddot`: each `(n,)` (one sample,
    /// returns `(n,)`) or `(N, n)` (returns `(N, n)`; the GIL is released). `out`: a
    /// float64 array of the returned shape to write into.
    #[pyo3(signature = (q, qdot, qddot, *, out=None))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
        qddot: &Bound<'py, PyAny>,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let n = self.joints();
        if self.model.d_in() != 3 * n {
            return Err(value_error(format!(
                "this network has {} inputs and {n} outputs, not the observer's [q, qdot, qddot] -> tau",
                self.model.d_in()
            )));
        }
        let (q, rq, single) = rows(q, "q", n, true)?;
        let (qd, rqd, single_d) = rows(qdot, "qdot", n, true)?;
        let (qdd, rqdd, single_dd) = rows(qddot, "qddot", n, true)?;
        if rq != rqd || rq != rqdd || single != single_d || single != single_dd {
            return Err(value_error(format!(
                "`q`, `qdot` and `qddot` must have the same shape, (n,) or (N, {n})"
            )));
        }
        let mut x = Vec::with_capacity(rq * 3 * n);
        for r in 0..rq {
            for s in [&q, &qd, &qdd] {
                x.extend_from_slice(&s[r * n..(r + 1) * n]);
            }
        }
        let net = &self.model;
        let mut y = vec![0.0; rq * n];
        py.detach(|| net.predict_batch(&x, &mut y))
            .map_err(broad_error)?;
        if single {
            Ok(vector_out(py, &y, out, "out")?.into_any())
        } else {
            Ok(matrix_out(py, (rq, n), |i, j| y[i * n + j], out, "out")?.into_any())
        }
    }

    /// Writes the network to `path` (versioned and checksummed; written to a temporary
    /// file and renamed into place). Loads with `load_network` and
    /// `admittance_learning::broad::BroadModel::load`.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let net = &self.model;
        py.detach(|| net.save(&path)).map_err(broad_error)
    }

    /// Gaussian enhancement nodes.
    #[getter]
    fn nodes(&self) -> usize {
        self.model.n_nodes()
    }

    /// Inputs per sample (3n: `[q, qdot, qddot]`).
    #[getter]
    fn n_inputs(&self) -> usize {
        self.model.d_in()
    }

    /// Outputs per sample (n: one torque per joint).
    #[getter]
    fn n_outputs(&self) -> usize {
        self.model.d_out()
    }

    /// Whether the network has the friction-shaped `tanh(qdot / v)` inputs.
    #[getter]
    fn friction_features(&self) -> bool {
        self.model.friction().count() > 0
    }

    /// The chosen ridge parameter (absolute).
    #[getter]
    fn ridge_lambda(&self) -> f64 {
        self.model.lambda()
    }

    /// Per-joint NRMSE on the validation rows (RMSE over the standard deviation of the
    /// target: 0 perfect, 1 no better than the mean), after training or the last `grow`;
    /// `None` for a loaded network.
    #[getter]
    fn validation_nrmse<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.validation_nrmse
            .as_ref()
            .map(|v| PyArray1::from_slice(py, v))
    }

    /// Training rows behind the network (`None` when it holds no growth state).
    #[getter]
    fn samples(&self) -> Option<usize> {
        self.samples
    }

    /// Validation rows (`None` for a loaded network; 0 under cross-validation, where
    /// every row is scored by a fit on the others).
    #[getter]
    fn validation_samples(&self) -> Option<usize> {
        self.validation_samples
    }

    /// Wall time of the fit (or of the last `grow`), s; `None` for a loaded network.
    #[getter]
    fn seconds(&self) -> Option<f64> {
        self.seconds
    }

    /// Whether the network can grow (it holds the training data's Gram matrix).
    #[getter]
    fn can_grow(&self) -> bool {
        self.model.has_growth_state()
    }

    fn __repr__(&self) -> String {
        format!(
            "Network(nodes={}, inputs={}, outputs={}, friction_features={})",
            self.model.n_nodes(),
            self.model.d_in(),
            self.model.d_out(),
            self.friction_features()
        )
    }
}

impl PyNetwork {
    /// The training metrics of `summary.json` for a loop observer on this network
    /// (`train_seconds`, `observer_nodes`, `validation_nrmse`, ...).
    pub(crate) fn training_metrics(&self) -> admittance_scenario::ObserverTrainingMetrics {
        admittance_scenario::ObserverTrainingMetrics {
            train_seconds: self.seconds.unwrap_or(0.0),
            observer_nodes: self.model.n_nodes(),
            validation_nrmse: self.validation_nrmse.clone().unwrap_or_default(),
            observer_model_cached: false,
            training_samples: self.samples.unwrap_or(0),
            observer_lambda: self.model.lambda(),
        }
    }
}
