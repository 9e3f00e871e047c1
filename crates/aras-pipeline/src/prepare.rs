//! One log's way to least squares, written once: process → stack the
//! regressor → the processing's zero-phase low-pass on the torques and the
//! regressor columns alike (`docs/processing.md`, "Parallel filtering").
//! The in-memory identification, every block of the streaming route and the
//! diagnosis's data sets start here; the diagnosis's bounded-memory pass
//! runs the regressor step alone, window by window.

use crate::PipelineError;
use aras_dyn::Model;
use aras_ident::{BaseParameters, IdentError};
use aras_kin::{Geometry, KinematicSample};
use aras_log::Log;
use aras_signal::{BandLimit, ProcessOptions, Processed, Sos};
use faer::{Mat, MatRef};

use crate::robot::{
    FilterMode, Stacked, filter, filter_columns, filter_reach, noise_gain, reversal_mask, stack,
    stack_selected,
};

/// Which columns of the model's regressor are stacked.
#[derive(Debug, Clone, Copy)]
pub enum RegressorColumns<'a> {
    /// Every standard column.
    Standard,
    /// The base columns only (`W_b = W E`), filtered alone: filtering acts
    /// column by column, so the values are those of filtering every standard
    /// column first, at a fraction of the cost.
    Base(&'a BaseParameters),
}

impl RegressorColumns<'_> {
    /// These columns of a stacked standard regressor `w`: `w` itself, or
    /// the base columns `W E`.
    fn select(self, w: MatRef<'_, f64>) -> Result<Mat<f64>, PipelineError> {
        match self {
            Self::Standard => Ok(w.to_owned()),
            Self::Base(base) => base.base_regressor(w).map_err(PipelineError::from),
        }
    }
}

/// The regressor step of [`prepare`] on kinematics that are evaluated once
/// and shared by several models (the diagnosis's windows: the current model
/// and every candidate): `model`'s `columns` on `kinematics`, joint-major,
/// then `low_pass` (the processing's filter, and whether the record is one
/// period, filtered circularly) on every column. The torques are left to
/// the caller, who filters them once per record.
pub(crate) fn columns_on(
    model: &Model,
    columns: RegressorColumns<'_>,
    kinematics: &[KinematicSample],
    low_pass: Option<(&Sos, bool)>,
) -> Result<Mat<f64>, PipelineError> {
    let n = kinematics.len();
    let w = model
        .stacked(kinematics)
        .map_err(|e| IdentError::external("stacking the regressor", e))?;
    let mut w = columns.select(MatRef::from_column_major_slice(
        w.as_slice(),
        2 * n,
        model.columns(),
    ))?;
    if let Some((sos, periodic)) = low_pass {
        filter_columns(&mut w, n, sos, periodic)?;
    }
    Ok(w)
}

/// A processed log with its stacked regressor and torques (`2N × n`, joint
/// 1's rows first), filtered as the processing's low-pass says.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// What `aras-signal` produced.
    pub processed: Processed,
    /// Stacked regressor and torques of every sample, filtered.
    pub stacked: Stacked,
    /// The zero-phase low-pass the processing applied to θ, applied here to
    /// the torques (and with [`FilterMode::Parallel`] every column); `None`
    /// when the processing filtered nothing (a harmonic series, logged
    /// derivatives, no filter).
    pub filter: Option<Sos>,
    /// The regressor before that filter, when one was applied and it was
    /// asked for: predictions compared with the raw torques use it.
    pub unfiltered: Option<Stacked>,
}

pub use aras_diagnose::{processing_filter, record_noise_gain};

/// Processes `log` (`aras_signal::process` with the model's task
/// coordinates), stacks `model`'s `columns` on the samples and applies the
/// processing's low-pass to torques and columns (`mode`); keeps a copy of
/// the unfiltered regressor when `keep_unfiltered` and a filter was applied.
pub fn prepare(
    log: &Log,
    opts: &ProcessOptions,
    model: &Model,
    geometry: &Geometry,
    mode: FilterMode,
    columns: RegressorColumns<'_>,
    keep_unfiltered: bool,
) -> Result<Prepared, PipelineError> {
    let (processed, mut stacked) = process_and_stack(log, opts, model, geometry, columns, None)?;
    let filter_sos = processing_filter(&processed.summary)?;
    let projected = matches!(processed.band_limit(), BandLimit::Harmonics(_));
    let unfiltered =
        (keep_unfiltered && (filter_sos.is_some() || projected)).then(|| stacked.clone());
    limit_stacked(
        &mut stacked,
        filter_sos.as_ref(),
        processed.band_limit(),
        mode,
        processed.summary.periods.is_some(),
    )?;
    Ok(Prepared {
        processed,
        stacked,
        filter: filter_sos,
        unfiltered,
    })
}

/// Applies the processing's band-limiting of θ to the stacked torques and
/// (with [`FilterMode::Parallel`]) columns: the zero-phase low-pass
/// `filter` (`periodic`: circular) when it applied one, else a harmonic
/// `band`, else nothing.
fn limit_stacked(
    stacked: &mut Stacked,
    filter_sos: Option<&Sos>,
    band: &BandLimit,
    mode: FilterMode,
    periodic: bool,
) -> Result<(), PipelineError> {
    match (filter_sos, band) {
        (Some(sos), _) => filter(stacked, sos, mode, periodic),
        (None, BandLimit::Harmonics(_)) => band_limit_stacked(stacked, band, mode),
        _ => Ok(()),
    }
}

/// Noise power gain of [`limit_stacked`]'s operator on a record of `n`
/// samples: the low-pass's ([`noise_gain`]) or, for one averaged block
/// projected on its harmonics, the projection's
/// (`aras_signal::HarmonicBand::noise_gain`); `None` when nothing was
/// band-limited.
fn operator_noise_gain(
    filter_sos: Option<&Sos>,
    band: &BandLimit,
    n: usize,
    periodic: bool,
) -> Result<Option<f64>, PipelineError> {
    match (filter_sos, band) {
        (Some(sos), _) => noise_gain(sos, n, periodic)
            .map(Some)
            .map_err(PipelineError::from),
        (None, BandLimit::Harmonics(h)) if h.rows.is_none() => Ok(Some(h.noise_gain())),
        _ => Ok(None),
    }
}

/// Applies a harmonic band ([`BandLimit::Harmonics`]) to each joint's block
/// of the torques and (with [`FilterMode::Parallel`]) of every regressor
/// column: the truncated series the angles passed is then the operator of
/// both sides of `T = W β`, as the low-pass is on the filtered route.
/// Without it the torques keep the acceleration content above the series'
/// highest harmonic that the regressor's inertial columns have lost.
fn band_limit_stacked(
    stacked: &mut Stacked,
    band: &BandLimit,
    mode: FilterMode,
) -> Result<(), PipelineError> {
    let n = stacked.groups.counts()[0];
    let err = |e| IdentError::external("band-limiting the stacked data", e);
    for g in 0..2 {
        band.apply(&mut stacked.t[g * n..(g + 1) * n])
            .map_err(err)?;
    }
    if mode == FilterMode::Parallel {
        band_limit_columns(&mut stacked.w, n, band)?;
    }
    Ok(())
}

/// Applies `band` to each joint's block (`n` rows) of every column of the
/// joint-major `w` that is not zero there, columns in parallel.
fn band_limit_columns(w: &mut Mat<f64>, n: usize, band: &BandLimit) -> Result<(), PipelineError> {
    use rayon::prelude::*;
    let nc = w.ncols();
    let cols: Vec<Vec<f64>> = (0..nc)
        .into_par_iter()
        .map(|c| {
            let mut col: Vec<f64> = (0..2 * n).map(|i| w[(i, c)]).collect();
            for g in 0..2 {
                let block = &mut col[g * n..(g + 1) * n];
                if block.iter().any(|v| *v != 0.0) {
                    band.apply(block)
                        .map_err(|e| IdentError::external("band-limiting a column", e))?;
                }
            }
            Ok(col)
        })
        .collect::<Result<_, IdentError>>()?;
    for (c, col) in cols.into_iter().enumerate() {
        for (i, v) in col.into_iter().enumerate() {
            w[(i, c)] = v;
        }
    }
    Ok(())
}

/// What accumulating a block needs: its filtered regressor and torques,
/// the rows kept away from velocity reversals, and the noise gain of its
/// band-limiting.
pub(crate) struct BlockRows {
    /// Stacked regressor and torques, filtered.
    pub stacked: Stacked,
    /// Rows kept ([`Prepared::keep_mask`]), joint-major.
    pub keep: Vec<bool>,
    /// Noise power gain of the low-pass or harmonic projection applied
    /// ([`Prepared::noise_gain`]); `None` when nothing was band-limited.
    pub noise_gain: Option<f64>,
    /// Samples per joint.
    pub n: usize,
}

/// [`prepare`] for accumulating a block: stacks into `recycled` (a previous
/// block's regressor of the same shape, whose pages the kernel would
/// otherwise map and clear again for every block), takes the reversal mask
/// from the processed samples and drops them before the regressor is
/// filtered, so a block's peak memory holds the regressor but not the
/// samples (15 channels) as well.
#[allow(clippy::too_many_arguments)]
pub(crate) fn prepare_block_rows(
    log: &Log,
    opts: &ProcessOptions,
    model: &Model,
    geometry: &Geometry,
    mode: FilterMode,
    columns: RegressorColumns<'_>,
    (min_speed, reach_tol): (f64, f64),
    recycled: Option<Mat<f64>>,
) -> Result<BlockRows, PipelineError> {
    let (processed, mut stacked) =
        process_and_stack(log, opts, model, geometry, columns, recycled)?;
    let filter_sos = processing_filter(&processed.summary)?;
    let periodic = processed.summary.periods.is_some();
    let n = processed.samples.len();
    let keep = record_keep_mask(
        &processed.samples.theta_dot,
        filter_sos.as_ref(),
        periodic,
        min_speed,
        reach_tol,
    )?;
    let noise_gain = operator_noise_gain(filter_sos.as_ref(), processed.band_limit(), n, periodic)?;
    let band = processed.band_limit().clone();
    drop(processed);
    limit_stacked(&mut stacked, filter_sos.as_ref(), &band, mode, periodic)?;
    Ok(BlockRows {
        stacked,
        keep,
        noise_gain,
        n,
    })
}

/// Processes `log` and stacks `model`'s `columns` on its samples (into
/// `recycled` when it has the shape), unfiltered.
fn process_and_stack(
    log: &Log,
    opts: &ProcessOptions,
    model: &Model,
    geometry: &Geometry,
    columns: RegressorColumns<'_>,
    recycled: Option<Mat<f64>>,
) -> Result<(Processed, Stacked), PipelineError> {
    let processed = aras_signal::process(log, opts, &aras_kin::task_motion(geometry))
        .map_err(|e| IdentError::external(format!("processing {}", log.name), e))?;
    let stacked = match columns {
        RegressorColumns::Standard => stack(model, geometry, &processed.samples)?,
        RegressorColumns::Base(base) if base.n_standard() != model.columns() => {
            return Err(IdentError::DimensionMismatch {
                what: "regressor columns",
                expected: base.n_standard(),
                found: model.columns(),
                hint: "the base parameters must come from the same model's analysis",
            }
            .into());
        }
        RegressorColumns::Base(base) => stack_selected(
            model,
            geometry,
            &processed.samples,
            (base.independent(), base.base_names()),
            recycled,
        )?,
    };
    Ok((processed, stacked))
}

impl Prepared {
    /// Samples per joint.
    pub fn n(&self) -> usize {
        self.processed.samples.len()
    }

    /// True when the record is one averaged block (filtered circularly).
    pub fn periodic(&self) -> bool {
        self.processed.summary.periods.is_some()
    }

    /// Stacked torques `[τ1; τ2]` (all rows).
    pub fn t(&self) -> &[f64] {
        &self.stacked.t
    }

    /// A faer view of the regressor.
    pub fn w_ref(&self) -> MatRef<'_, f64> {
        self.stacked.w.as_ref()
    }

    /// Noise power gain of the operator the torques and columns passed:
    /// the low-pass's ([`record_noise_gain`]) or, for an averaged block
    /// projected on its harmonics, the projection's
    /// (`aras_signal::HarmonicBand::noise_gain`). What
    /// `aras_ident::OlsEstimate::with_filtered_noise` corrects σ by.
    pub fn noise_gain(&self) -> Result<f64, PipelineError> {
        operator_noise_gain(
            self.filter.as_ref(),
            self.processed.band_limit(),
            self.n(),
            self.periodic(),
        )
        .map(|g| g.unwrap_or(1.0))
    }

    /// Puts joint-major columns (`2N` rows, e.g. a regressor column at a
    /// new setting) through the operator [`Self::stacked`]'s columns passed
    /// with `mode`: the low-pass, the harmonic projection of an averaged
    /// block, or nothing (torque-only filtering, no band-limiting), so a
    /// column swapped into the fit is treated like its neighbours.
    pub fn limit_columns(&self, w: &mut Mat<f64>, mode: FilterMode) -> Result<(), PipelineError> {
        if mode == FilterMode::TorqueOnly {
            return Ok(());
        }
        let n = self.n();
        if let Some(sos) = &self.filter {
            return filter_columns(w, n, sos, self.periodic()).map_err(PipelineError::from);
        }
        match self.processed.band_limit() {
            band @ BandLimit::Harmonics(_) => band_limit_columns(w, n, band),
            _ => Ok(()),
        }
    }

    /// Puts one joint's per-sample torque series through the operator
    /// [`Self::stacked`]'s torques passed (the low-pass or the harmonic
    /// projection; either filtering mode applies it to the torques).
    pub fn limit_torque(&self, tau: &mut [f64]) -> Result<(), PipelineError> {
        if let Some(sos) = &self.filter {
            let y = sos
                .filtfilt_record(tau, self.periodic())
                .map_err(|e| IdentError::external("filtering a torque series", e))?;
            tau.copy_from_slice(&y);
            return Ok(());
        }
        match self.processed.band_limit() {
            band @ BandLimit::Harmonics(_) => band
                .apply(tau)
                .map_err(|e| IdentError::external("band-limiting a torque series", e))
                .map_err(PipelineError::from),
            _ => Ok(()),
        }
    }

    /// Rows kept away from velocity reversals: joint `j`'s rows with
    /// `|θ̇_j| < min_speed` are dropped
    /// ([`reversal_mask`]), widened by
    /// the regressor filter's reach down to `reach_tol` of its
    /// impulse-response peak, because filtering spreads the misfit at a
    /// reversal in time.
    /// Joint-major, like [`Self::stacked`].
    pub fn keep_mask(&self, min_speed: f64, reach_tol: f64) -> Result<Vec<bool>, PipelineError> {
        record_keep_mask(
            &self.processed.samples.theta_dot,
            self.filter.as_ref(),
            self.periodic(),
            min_speed,
            reach_tol,
        )
    }
}

/// Rows of a record kept away from velocity reversals ([`reversal_mask`]):
/// joint `j`'s rows with `|θ̇_j| < min_speed` are dropped, widened by the
/// zero-phase `filter`'s reach down to `reach_tol` of its impulse-response
/// peak ([`filter_reach`]; no widening unfiltered), because filtering
/// spreads the misfit at a reversal in time. Joint-major.
pub(crate) fn record_keep_mask(
    theta_dot: &[Vec<f64>],
    filter: Option<&Sos>,
    periodic: bool,
    min_speed: f64,
    reach_tol: f64,
) -> Result<Vec<bool>, PipelineError> {
    let n = theta_dot[0].len();
    let reach = match filter {
        Some(sos) => filter_reach(sos, n, periodic, reach_tol)?,
        None => 0,
    };
    reversal_mask(theta_dot, min_speed, reach, periodic).map_err(PipelineError::from)
}
