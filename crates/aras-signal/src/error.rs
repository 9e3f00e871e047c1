//! Typed errors. Every message says what was wrong, where (file, line,
//! column, key, value) and how to fix it. A variant with an underlying error
//! returns it from [`source`](std::error::Error::source) and does not repeat
//! it in its own message, so printing the chain shows each cause once.

/// Errors of filter design and filtering.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FilterError {
    /// Filter order outside `1..=max`.
    #[error("filter order {order} is invalid: use an order from 1 to {max}")]
    InvalidOrder {
        /// The requested order.
        order: usize,
        /// Largest supported order.
        max: usize,
    },
    /// Sample rate not a positive finite number.
    #[error("sample rate {value} Hz is invalid: it must be a positive finite number")]
    InvalidSampleRate {
        /// The offending value (Hz).
        value: f64,
    },
    /// Cut-off outside (0, Nyquist).
    #[error(
        "cut-off {cutoff_hz} Hz is invalid: it must lie strictly between 0 and the Nyquist \
         frequency {nyquist_hz} Hz (half the sample rate {sample_rate_hz} Hz)"
    )]
    InvalidCutoff {
        /// The requested cut-off (Hz).
        cutoff_hz: f64,
        /// Half the sample rate (Hz).
        nyquist_hz: f64,
        /// The sample rate (Hz).
        sample_rate_hz: f64,
    },
    /// A filter coefficient row is unusable.
    #[error("filter section {section} is invalid: {reason}")]
    InvalidSection {
        /// Index of the section (0 for a transfer function).
        section: usize,
        /// What is wrong and how to fix it.
        reason: String,
    },
    /// Signal not longer than the odd-extension pad length (scipy raises too).
    #[error(
        "signal of {len} samples is too short for zero-phase filtering: it must be longer than \
         padlen = {padlen} (as scipy's sosfiltfilt/filtfilt require); use a lower filter order \
         or a longer record"
    )]
    TooShort {
        /// Length of the signal.
        len: usize,
        /// Required minimum length minus one.
        padlen: usize,
    },
    /// A sample of the input is NaN or infinite.
    #[error("sample {index} of the signal is not finite ({value}): filter only finite data")]
    NonFinite {
        /// Index of the first non-finite sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// Signals filtered together differ in length.
    #[error(
        "signal {index} has {len} samples but signal 0 has {first}: filter signals of equal \
         length together"
    )]
    UnequalSignals {
        /// Length of the first signal.
        first: usize,
        /// Index of the first signal of another length.
        index: usize,
        /// Its length.
        len: usize,
    },
    /// Output buffer length differs from the input length.
    #[error("output buffer has {output} samples but the input has {input}: give equal lengths")]
    LengthMismatch {
        /// Input length.
        input: usize,
        /// Output length.
        output: usize,
    },
}

/// Errors of [`process`](crate::process).
#[derive(Debug, thiserror::Error)]
pub enum ProcessError {
    /// Filter design or filtering failed.
    #[error("{context}: the filter failed")]
    Filter {
        /// What was being filtered.
        context: String,
        /// The filter error.
        #[source]
        source: FilterError,
    },
    /// An option value is invalid.
    #[error("invalid process option {name} = {value}: {reason}")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// Its value.
        value: String,
        /// What is allowed.
        reason: String,
    },
    /// The record is too short for what was asked.
    #[error("{what}: the record has {have} samples but {need} are needed; {hint}")]
    TooShort {
        /// The step that needs more data.
        what: String,
        /// Samples available.
        have: usize,
        /// Samples needed.
        need: usize,
        /// How to fix it.
        hint: String,
    },
    /// The period is not a whole number of samples.
    #[error(
        "period {period_s} s is {samples:.4} samples at the log's step {step_s} s, not a whole \
         number (the periods would drift by {drift:.2} samples over the record), and no block of \
         several periods that fits in the record is a whole number of samples either; check \
         excitation.period_s, record more periods, or resample the log"
    )]
    PeriodNotWhole {
        /// Period (s).
        period_s: f64,
        /// Samples per period (fractional).
        samples: f64,
        /// Sample step (s).
        step_s: f64,
        /// Accumulated drift over all periods (samples).
        drift: f64,
    },
    /// One period (block of periods) differs too much from the average.
    #[error(
        "period block {index} (t = {t_start:.3}–{t_end:.3} s) of {channel} differs from the average \
         period by {relative_percent:.1}% RMS (limit {limit_percent:.1}%): the motion is not \
         periodic with period {period_s} s; check excitation.period_s and the settling time"
    , relative_percent = relative * 100.0, limit_percent = limit * 100.0)]
    PeriodsDisagree {
        /// Channel name.
        channel: String,
        /// 0-based index of the period.
        index: usize,
        /// Its first time.
        t_start: f64,
        /// Its last time.
        t_end: f64,
        /// RMS deviation relative to the channel's variation.
        relative: f64,
        /// The limit.
        limit: f64,
        /// The period (s).
        period_s: f64,
    },
    /// Resampling would have to bridge gaps longer than allowed.
    #[error(
        "{file}: {count} gap(s) in the time stamps longer than the {max_gap_s} s that resampling \
         may bridge:{list}\nsplit the log at the gaps, or raise the limit (--max-gap, config \
         log.max_gap_s) if interpolating across them is acceptable"
    )]
    GapTooLong {
        /// Log name.
        file: String,
        /// Gaps beyond the limit.
        count: usize,
        /// One line per gap (the first few), each starting with a newline.
        list: String,
        /// The limit (s).
        max_gap_s: f64,
    },
    /// The log has another number of joints than the model's coordinates
    /// take.
    #[error(
        "{log} has {joints} joint(s) but the model's coordinates take {expected}: give a log of \
         this robot (columns theta1 … theta{expected}), or read it with \
         ReadOptions::joints = Some({expected})"
    )]
    Joints {
        /// The log's name.
        log: String,
        /// Its joints.
        joints: usize,
        /// The coordinates' dimension.
        expected: usize,
    },
    /// The model's coordinates could not be computed at a sample
    /// ([`Coordinates`](crate::Coordinates), e.g. a pose the kinematics reject).
    #[error("the model's coordinates failed at t = {t} s (sample {index})")]
    Coordinates {
        /// Sample index in the output.
        index: usize,
        /// Its time.
        t: f64,
        /// The mapping's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The log's derivative columns, asked to be used, contradict its
    /// angles ([`aras_log::units::check_derivative_column`]).
    #[error("the logged derivatives cannot be used")]
    LoggedDerivatives {
        /// Which column, its ratio and the fix.
        #[source]
        source: aras_log::LogError,
    },
}
