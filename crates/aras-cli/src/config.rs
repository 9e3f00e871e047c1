//! The configuration file: every setting of every stage, in TOML or JSON
//! (chosen by the file's extension), documented key by key in
//! `docs/config.md`.
//!
//! Reading is strict (`deny_unknown_fields` everywhere): a misspelt key is
//! an error, never a silently ignored setting. Every error names the file,
//! the dotted key (`signal.cutoff_hz`) and its line, and says how to fix it.
//! Missing keys take the defaults of [`Config::default`], which
//! `aras pipeline --print-config` prints.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// The whole configuration. Units: SI, angles in degrees only where a key
/// says `_deg`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Config {
    /// The robot (nominal / CAD parameters).
    pub robot: RobotConfig,
    /// The excitation trajectory design ((74)–(77), `docs/excitation.md`).
    pub trajectory: TrajectoryConfig,
    /// The simulated robot (`docs/simulator.md`).
    pub simulation: SimulationConfig,
    /// Reading a lab's log: time unit, glitches, resampling
    /// (`docs/log-format.md`).
    pub log: LogConfig,
    /// Signal processing (`docs/processing.md`).
    pub signal: SignalConfig,
    /// Identification ((58)–(73), `docs/model.md`).
    pub identification: IdentificationConfig,
    /// Validation ((78)–(80), `docs/validation.md`).
    pub validation: ValidationConfig,
    /// The discrepancy diagnosis's selection (`docs/diagnose.md`).
    pub diagnose: DiagnoseConfig,
    /// Joint friction (`aras friction`, `docs/friction.md`).
    pub friction: FrictionConfig,
}

/// `[friction]` is the library's friction-analysis settings
/// (`aras_friction::analyse`), defaults and checks included;
/// `[friction.fit]` the model fits, `[friction.library]` the candidate
/// effects of its diagnosis.
pub use aras_friction::FrictionSettings as FrictionConfig;

/// `[diagnose]`: the forward selection of missing effects
/// (`aras_pipeline::diagnose::DiagnoseOptions`, whose defaults these are).
/// The rows it fits are identification's (`[identification]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DiagnoseConfig {
    /// Family-wise significance level of one round.
    pub alpha: f64,
    /// Smallest validation fitness gain (points of (78), mean over the
    /// joints) a candidate must bring on every validation log.
    pub min_gain: f64,
    /// At most this many effects are added.
    pub max_steps: usize,
    /// The candidates and their grids.
    pub grid: aras_pipeline::diagnose::CandidateGrid,
}

impl Default for DiagnoseConfig {
    fn default() -> Self {
        let d = aras_pipeline::diagnose::DiagnoseOptions::default();
        Self {
            alpha: d.alpha,
            min_gain: d.min_gain,
            max_steps: d.max_steps,
            grid: d.grid,
        }
    }
}

/// `[robot]`: which robot, and overrides of its geometry and gravity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotConfig {
    /// `"default"` (the embedded ARAS-Diamond, `docs/model.md`) or the path of a
    /// parameter file (`docs/parameter-format.md`), relative to the config
    /// file's directory.
    pub params: String,
    /// Overrides the parameter file's proximal arc α (deg).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_deg: Option<f64>,
    /// Overrides the parameter file's distal arc β (deg).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta_deg: Option<f64>,
    /// Overrides the gravity vector in the base frame (m/s²).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gravity: Option<[f64; 3]>,
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self {
            params: "default".into(),
            alpha_deg: None,
            beta_deg: None,
            gravity: None,
        }
    }
}

/// Design criterion of the excitation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CriterionChoice {
    /// Condition number of the column-scaled base regressor (the paper's).
    Condition,
    /// D-optimality (`−ln det` of the information matrix).
    DOptimal,
}

/// `[trajectory]`: the Fourier excitation (74)–(77).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrajectoryConfig {
    /// Harmonics L (paper: 5).
    pub harmonics: usize,
    /// Base period 2π/ω_f (s; paper: 10).
    pub period_s: f64,
    /// Design criterion.
    pub criterion: CriterionChoice,
    /// Random feasible starts of the multi-start optimisation.
    pub starts: usize,
    /// Seed of the starts.
    pub seed: u64,
    /// Regressor samples per period for the criterion.
    pub criterion_points: usize,
    /// Constraint grid points per period.
    pub constraint_points: usize,
    /// Outer (ALM) iterations per start.
    pub max_outer_iterations: usize,
    /// Inner (PANOC) iterations per outer iteration.
    pub max_inner_iterations: usize,
    /// Workspace box (77): `[φ_min, γ_min]` (deg).
    pub min_deg: [f64; 2],
    /// Workspace box (77): `[φ_max, γ_max]` (deg).
    pub max_deg: [f64; 2],
    /// Rate limits `|Ẋ|` (deg/s).
    pub max_rate_deg_s: [f64; 2],
    /// Acceleration limits `|Ẍ|` (deg/s²).
    pub max_accel_deg_s2: [f64; 2],
}

impl Default for TrajectoryConfig {
    fn default() -> Self {
        Self {
            harmonics: 5,
            period_s: 10.0,
            criterion: CriterionChoice::Condition,
            // aras-excite's default. Measured: 8 starts take ≈ 4–5 s on this
            // 2-core machine, well inside the pipeline's 20 s budget.
            starts: 8,
            seed: 1,
            criterion_points: 100,
            constraint_points: 200,
            max_outer_iterations: 20,
            max_inner_iterations: 200,
            min_deg: [30.0, 40.0],
            max_deg: [140.0, 80.0],
            max_rate_deg_s: [200.0, 200.0],
            max_accel_deg_s2: [800.0, 800.0],
        }
    }
}

/// `[simulation]`: the simulated robot standing in for hardware.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimulationConfig {
    /// Periods of the excitation to simulate (paper: 16).
    pub periods: usize,
    /// Time (s) the simulated robot tracks the trajectory before the log
    /// starts, so the log holds no start-up transient; the first row is
    /// the trajectory's phase 0 (0: log from the start-up).
    pub lead_in_s: f64,
    /// Controller and log rate (Hz).
    pub rate_hz: f64,
    /// RK4 substeps per log sample.
    pub substeps: usize,
    /// PD proportional gains (N·m/rad).
    pub kp: [f64; 2],
    /// PD derivative gains (N·m·s/rad).
    pub kd: [f64; 2],
    /// Cut-off of the controller's velocity filter (Hz).
    pub velocity_cutoff_hz: f64,
    /// Model feedforward with the nominal robot (the paper: pure PD).
    pub feedforward: bool,
    /// Torque limits (N·m).
    pub torque_limit: [f64; 2],
    /// Friction smoothing width `w` of `tanh(θ̇/w)` (rad/s).
    pub friction_smoothing: f64,
    /// LuGre friction in place of the smoothed Coulomb term (absent: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lugre: Option<aras_dyn::sim::LuGre>,
    /// Current-sense noise standard deviation (A).
    pub current_noise_std_a: [f64; 2],
    /// Motor torque constants (N·m/A).
    pub torque_constants: [f64; 2],
    /// Capstan ratios.
    pub gear_ratios: [f64; 2],
    /// Encoder counts per motor revolution.
    pub counts_per_rev: [u32; 2],
    /// Torque samples lag the angles by this many samples.
    pub torque_delay_samples: usize,
    /// And by this further fraction of a sample, in `[0, 1)`.
    pub torque_delay_fraction: f64,
    /// Noise seed.
    pub seed: u64,
    /// The simulated robot's true parameters when they differ from
    /// `robot.params` (e.g. a file with `extra` effects); path relative to
    /// the config file. Absent: the nominal robot is the truth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<String>,
}

impl Default for SimulationConfig {
    fn default() -> Self {
        let s = aras_dyn::sim::SimConfig::default();
        Self {
            periods: 16,
            lead_in_s: s.lead_in_s,
            rate_hz: s.output_rate_hz,
            substeps: s.substeps,
            kp: s.controller.kp,
            kd: s.controller.kd,
            velocity_cutoff_hz: s.controller.velocity_cutoff_hz,
            feedforward: false,
            torque_limit: s.torque_limit,
            friction_smoothing: s.friction_smoothing,
            lugre: None,
            current_noise_std_a: s.sensors.current_noise_std,
            torque_constants: s.sensors.torque_constants,
            gear_ratios: s.sensors.gear_ratios,
            counts_per_rev: s.sensors.counts_per_rev,
            torque_delay_samples: 0,
            torque_delay_fraction: 0.0,
            seed: 1,
            truth: None,
        }
    }
}

/// How velocities and accelerations are obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DerivativeChoice {
    /// Spectral for an averaged periodic record, central differences otherwise.
    Auto,
    /// Central differences (the paper).
    CentralDifference,
    /// Savitzky–Golay (`sg_half_window`, `sg_poly_order`).
    SavitzkyGolay,
    /// Frequency-domain differentiation (periodic records).
    Spectral,
}

/// How `[signal]` chooses the processing's bandwidth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BandwidthMode {
    /// A zero-phase Butterworth at `cutoff_hz` (`aras_signal::Bandwidth::Fixed`).
    Fixed,
    /// Chosen from the data (`aras_signal::Bandwidth::Auto`: a harmonic
    /// series up to the noise floor for a periodic log, else a cut-off
    /// that follows the angle spectrum; `docs/processing.md`).
    Auto,
}

/// `[log]`: how a lab's log is read before processing (`docs/log-format.md`):
/// the unit of `t`, what to do with isolated glitches, and resampling onto a
/// uniform grid, the torque timing. The command line's `--time-unit`,
/// `--glitches`, `--resample`, `--max-gap` and `--torques` override these.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LogConfig {
    /// Unit of `t`: `"s"`, `"ms"`, `"us"`, `"ns"`. Absent: seconds, and a
    /// whole-number step at a rate below 10 Hz is refused with the question
    /// whether t is in seconds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_unit: Option<aras_log::TimeUnit>,
    /// Isolated glitches: `"warn"` (default), `"refuse"`, `"drop"`,
    /// `"repair"`, `"off"`.
    pub glitches: aras_log::GlitchAction,
    /// Residual (robust standard deviations) beyond which an isolated
    /// sample is a glitch.
    pub glitch_threshold: f64,
    /// The robot's torque limits (N·m): a torque beyond
    /// `torque_limit_factor` times them is a glitch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub torque_limit: Option<[f64; 2]>,
    /// Factor on `torque_limit`.
    pub torque_limit_factor: f64,
    /// Resample the log onto a uniform grid at its nominal step before
    /// processing (gaps reported, none bridged beyond `max_gap_s`).
    pub resample: bool,
    /// Longest gap (s) the resampling interpolates across.
    pub max_gap_s: f64,
    /// What the logged torques are: `"sampled"` (measured at the sample
    /// times) or `"held"` (commands held until the next sample). Absent:
    /// as the log's sidecar states (`torques`), else sampled. A value
    /// contradicting the sidecar is refused.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub torques: Option<aras_log::TorqueTiming>,
}

impl Default for LogConfig {
    fn default() -> Self {
        let g = aras_log::GlitchOptions::default();
        Self {
            time_unit: None,
            glitches: g.action,
            glitch_threshold: g.threshold,
            torque_limit: g.torque_limit.and_then(|l| l.try_into().ok()),
            torque_limit_factor: g.limit_factor,
            resample: false,
            max_gap_s: aras_signal::ResampleOptions::default().max_gap_s,
            torques: aras_log::ReadOptions::default().torques,
        }
    }
}

impl LogConfig {
    /// The glitch detector's options.
    pub fn glitch_options(&self) -> aras_log::GlitchOptions {
        aras_log::GlitchOptions {
            action: self.glitches,
            threshold: self.glitch_threshold,
            torque_limit: self.torque_limit.map(|l| l.to_vec()),
            limit_factor: self.torque_limit_factor,
        }
    }
}

/// `[signal]`: processing of the logs (`docs/processing.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SignalConfig {
    /// Butterworth order of one pass.
    pub filter_order: usize,
    /// How the processing's bandwidth is chosen.
    pub bandwidth: BandwidthMode,
    /// Cut-off (Hz) of the zero-phase low-pass when `bandwidth` is
    /// `fixed`; 0 disables filtering.
    pub cutoff_hz: f64,
    /// Seconds dropped at the start before period averaging.
    pub settling_s: f64,
    /// Largest accepted relative RMS spread of θ between periods.
    pub max_period_spread: f64,
    /// Derivative method.
    pub derivative: DerivativeChoice,
    /// Savitzky–Golay half window (samples).
    pub sg_half_window: usize,
    /// Savitzky–Golay polynomial order.
    pub sg_poly_order: usize,
}

impl Default for SignalConfig {
    fn default() -> Self {
        Self {
            filter_order: 4,
            bandwidth: BandwidthMode::Auto,
            cutoff_hz: 10.0,
            settling_s: 0.0,
            max_period_spread: 0.1,
            derivative: DerivativeChoice::Auto,
            sg_half_window: 10,
            sg_poly_order: 3,
        }
    }
}

/// `[identification]` is the library's identification settings
/// (`aras_pipeline::identify`), defaults included; `[identification.sdp]`
/// its SDP options.
pub use aras_pipeline::identify::{
    IdentifySettings as IdentificationConfig, SdpOptions as SdpConfig, Weighting,
};
/// Which signals the low-pass is applied to before the fit.
pub use aras_pipeline::robot::FilterMode as FilteringMode;

/// `[validation]` is the library's validation settings
/// (`aras_pipeline::validate`), defaults included.
pub use aras_pipeline::validate::ValidationSettings as ValidationConfig;

/// A configuration error: file, dotted key, line, what and how to fix.
#[derive(Debug, Clone, PartialEq)]
pub struct ConfigError {
    /// The file (or `<defaults>`).
    pub file: String,
    /// The dotted key, if known.
    pub key: Option<String>,
    /// 1-based line, if known.
    pub line: Option<usize>,
    /// 1-based column, if known.
    pub column: Option<usize>,
    /// The message (what is wrong and how to fix it).
    pub message: String,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
        }
        if let Some(k) = &self.key {
            write!(f, ": key `{k}`")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for ConfigError {}

/// File formats of the configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// `.toml`
    Toml,
    /// `.json`
    Json,
}

/// A loaded configuration and where it came from (relative paths inside it
/// are resolved against `dir`).
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The settings.
    pub config: Config,
    /// Directory of the file (for relative paths); `.` for the defaults.
    pub dir: PathBuf,
}

impl Config {
    /// Reads and validates a configuration file (TOML or JSON by extension).
    pub fn load(path: &Path) -> Result<Loaded, ConfigError> {
        let file = path.display().to_string();
        let fail = |message: String| ConfigError {
            file: file.clone(),
            key: None,
            line: None,
            column: None,
            message,
        };
        let format = match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("toml") => Format::Toml,
            Some(e) if e.eq_ignore_ascii_case("json") => Format::Json,
            _ => {
                return Err(fail(
                    "unknown config format: the file name must end in .toml or .json".into(),
                ));
            }
        };
        let text = std::fs::read_to_string(path).map_err(|e| fail(format!("cannot read: {e}")))?;
        let config = Self::parse(&text, format, &file)?;
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_path_buf();
        Ok(Loaded { config, dir })
    }

    /// Parses and validates configuration text; `file` labels errors.
    pub fn parse(text: &str, format: Format, file: &str) -> Result<Self, ConfigError> {
        let keys = key_positions(text, format);
        let (config, err): (Option<Config>, Option<(String, Option<usize>)>) = match format {
            Format::Toml => match toml::from_str::<Config>(text) {
                Ok(c) => (Some(c), None),
                Err(e) => (
                    None,
                    Some((e.message().trim().to_string(), e.span().map(|s| s.start))),
                ),
            },
            Format::Json => match serde_json::from_str::<Config>(text) {
                Ok(c) => (Some(c), None),
                Err(e) => {
                    let full = e.to_string();
                    let suffix = format!(" at line {} column {}", e.line(), e.column());
                    let msg = full.strip_suffix(&suffix).unwrap_or(&full).to_string();
                    (None, Some((msg, offset_of(text, e.line(), e.column()))))
                }
            },
        };
        if let Some((message, offset)) = err {
            let key = offset.and_then(|o| {
                keys.iter()
                    .filter(|(_, p)| *p <= o)
                    .max_by_key(|(_, p)| *p)
                    .map(|(k, _)| k.clone())
            });
            let (line, column) = offset.map(|o| line_col(text, o)).unzip();
            let advice = if message.contains("unknown field") || message.contains("unknown variant")
            {
                "; remove or rename it (see docs/config.md, or `aras pipeline --print-config`)"
            } else if message.contains("invalid type") {
                "; see docs/config.md for the expected type and unit"
            } else {
                ""
            };
            return Err(ConfigError {
                file: file.into(),
                key,
                line,
                column,
                message: format!("{message}{advice}"),
            });
        }
        let config = config.expect("parsed");
        if let Err((key, message)) = config.validate() {
            let pos = keys.iter().find(|(k, _)| *k == key).map(|(_, p)| *p);
            let (line, column) = pos.map(|o| line_col(text, o)).unzip();
            return Err(ConfigError {
                file: file.into(),
                key: Some(key),
                line,
                column,
                message,
            });
        }
        Ok(config)
    }

    /// These settings as TOML (what `--print-config` prints: the defaults,
    /// or the `--config` file's settings with the defaults filled in).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot print: {e}\n"))
    }

    /// Checks every value; the error names the dotted key and the rule.
    pub fn validate(&self) -> Result<(), (String, String)> {
        self.check_robot()?;
        self.check_trajectory()?;
        self.check_simulation()?;
        self.check_log()?;
        self.check_signal()?;
        self.check_identification()?;
        self.check_diagnose()?;
        self.check_validation()
    }

    /// The fixed low-pass cut-off (Hz), 0 with the data-chosen bandwidth.
    fn fixed_cutoff_hz(&self) -> f64 {
        match self.signal.bandwidth {
            BandwidthMode::Fixed => self.signal.cutoff_hz,
            BandwidthMode::Auto => 0.0,
        }
    }

    /// `[robot]` checked.
    fn check_robot(&self) -> Result<(), (String, String)> {
        let r = &self.robot;
        if r.params.trim().is_empty() {
            return bad(
                "robot.params",
                "give \"default\" or a parameter file path".into(),
            );
        }
        for (k, v) in [
            ("robot.alpha_deg", r.alpha_deg),
            ("robot.beta_deg", r.beta_deg),
        ] {
            if let Some(v) = v
                && !(v > 0.0 && v < 180.0)
            {
                return bad(k, format!("an arc must lie in (0°, 180°), found {v}"));
            }
        }
        if let Some(g) = r.gravity
            && g.iter().any(|v| !v.is_finite())
        {
            return bad(
                "robot.gravity",
                "must be three finite numbers (m/s²)".into(),
            );
        }
        Ok(())
    }

    /// `[trajectory]` checked.
    fn check_trajectory(&self) -> Result<(), (String, String)> {
        let t = &self.trajectory;
        if !(1..=20).contains(&t.harmonics) {
            return bad(
                "trajectory.harmonics",
                format!("must be 1–20 (paper: 5), found {}", t.harmonics),
            );
        }
        pos("trajectory.period_s", t.period_s)?;
        if t.starts == 0 {
            return bad("trajectory.starts", "at least one start is needed".into());
        }
        if t.criterion_points < 2 * t.harmonics + 1 {
            return bad(
                "trajectory.criterion_points",
                format!("must be at least 2·harmonics + 1 = {}", 2 * t.harmonics + 1),
            );
        }
        if t.constraint_points < 10 {
            return bad("trajectory.constraint_points", "must be at least 10".into());
        }
        for i in 0..2 {
            let c = ["phi", "gamma"][i];
            if !(t.min_deg[i].is_finite()
                && t.max_deg[i].is_finite()
                && t.min_deg[i] < t.max_deg[i])
            {
                return bad(
                    "trajectory.min_deg",
                    format!(
                        "{c}: the box must be finite with min < max (trajectory.max_deg), found [{}, {}]",
                        t.min_deg[i], t.max_deg[i]
                    ),
                );
            }
            pos("trajectory.max_rate_deg_s", t.max_rate_deg_s[i])?;
            pos("trajectory.max_accel_deg_s2", t.max_accel_deg_s2[i])?;
        }
        Ok(())
    }

    /// `[simulation]` checked.
    fn check_simulation(&self) -> Result<(), (String, String)> {
        let s = &self.simulation;
        if s.periods == 0 {
            return bad("simulation.periods", "simulate at least one period".into());
        }
        pos("simulation.rate_hz", s.rate_hz)?;
        nonneg("simulation.lead_in_s", s.lead_in_s)?;
        if s.substeps == 0 {
            return bad("simulation.substeps", "at least 1".into());
        }
        pos("simulation.velocity_cutoff_hz", s.velocity_cutoff_hz)?;
        pos("simulation.friction_smoothing", s.friction_smoothing)?;
        for j in 0..2 {
            nonneg("simulation.kp", s.kp[j])?;
            nonneg("simulation.kd", s.kd[j])?;
            pos("simulation.torque_limit", s.torque_limit[j])?;
            nonneg("simulation.current_noise_std_a", s.current_noise_std_a[j])?;
            pos("simulation.torque_constants", s.torque_constants[j])?;
            pos("simulation.gear_ratios", s.gear_ratios[j])?;
            pos("simulation.counts_per_rev", s.counts_per_rev[j] as f64)?;
        }
        Ok(())
    }

    /// `[log]` checked.
    fn check_log(&self) -> Result<(), (String, String)> {
        let l = &self.log;
        pos("log.glitch_threshold", l.glitch_threshold)?;
        if !(l.torque_limit_factor.is_finite() && l.torque_limit_factor >= 1.0) {
            return bad(
                "log.torque_limit_factor",
                format!("must be ≥ 1, found {}", l.torque_limit_factor),
            );
        }
        if let Some(t) = l.torque_limit {
            for v in t {
                pos("log.torque_limit", v)?;
            }
        }
        pos("log.max_gap_s", l.max_gap_s)?;
        Ok(())
    }

    /// `[signal]` checked.
    fn check_signal(&self) -> Result<(), (String, String)> {
        let s = &self.simulation;
        let g = &self.signal;
        if !(1..=aras_signal::MAX_ORDER).contains(&g.filter_order) {
            return bad(
                "signal.filter_order",
                format!(
                    "must be 1–{}, found {}",
                    aras_signal::MAX_ORDER,
                    g.filter_order
                ),
            );
        }
        let cutoff = self.fixed_cutoff_hz();
        nonneg("signal.cutoff_hz", g.cutoff_hz)?;
        if cutoff > 0.0 && cutoff >= 0.5 * s.rate_hz {
            return bad(
                "signal.cutoff_hz",
                format!(
                    "must be below the Nyquist frequency {} Hz of simulation.rate_hz",
                    0.5 * s.rate_hz
                ),
            );
        }
        nonneg("signal.settling_s", g.settling_s)?;
        pos("signal.max_period_spread", g.max_period_spread)?;
        if g.derivative == DerivativeChoice::SavitzkyGolay
            && !(g.sg_half_window >= 1
                && g.sg_poly_order >= 2
                && g.sg_poly_order <= 2 * g.sg_half_window)
        {
            return bad(
                "signal.sg_poly_order",
                "Savitzky–Golay needs sg_half_window ≥ 1 and 2 ≤ sg_poly_order ≤ 2·sg_half_window"
                    .into(),
            );
        }
        Ok(())
    }

    /// `[identification]` checked.
    fn check_identification(&self) -> Result<(), (String, String)> {
        let i = &self.identification;
        if i.base_samples < 100 {
            return bad(
                "identification.base_samples",
                "use at least 100 quasi-random samples (default 400)".into(),
            );
        }
        nonneg("identification.min_speed", i.min_speed)?;
        fraction("identification.reversal_reach", i.reversal_reach)?;
        if let Err(e) = i.width.validate() {
            return bad(
                "identification.width",
                format!(
                    "{e} (found min = {}, max = {}, rounds = {})",
                    i.width.min, i.width.max, i.width.rounds
                ),
            );
        }
        let d = &i.sdp;
        nonneg("identification.sdp.epsilon", d.epsilon)?;
        if !(d.mass_tolerance.is_finite() && d.mass_tolerance >= 0.0 && d.mass_tolerance < 1.0) {
            return bad(
                "identification.sdp.mass_tolerance",
                format!("must lie in [0, 1), found {}", d.mass_tolerance),
            );
        }
        if let Some([lo, hi]) = d.box_bounds
            && !(hi.is_finite() && (0.0..=1.0).contains(&lo) && hi >= 1.0)
        {
            return bad(
                "identification.sdp.box_bounds",
                format!(
                    "give [lower ≤ 1, upper ≥ 1] factors such as [0.8, 1.25], found [{lo}, {hi}]"
                ),
            );
        }
        pos("identification.sdp.regularisation", d.regularisation)?;
        pos("identification.sdp.tolerance", d.tolerance)?;
        if d.max_iter == 0 {
            return bad("identification.sdp.max_iter", "at least 1".into());
        }
        Ok(())
    }

    /// `[diagnose]` checked.
    fn check_diagnose(&self) -> Result<(), (String, String)> {
        let d = &self.diagnose;
        if !(d.alpha.is_finite() && d.alpha > 0.0 && d.alpha < 1.0) {
            return bad(
                "diagnose.alpha",
                format!(
                    "must be a significance level in (0, 1) such as 0.01, found {}",
                    d.alpha
                ),
            );
        }
        nonneg("diagnose.min_gain", d.min_gain)?;
        if d.max_steps == 0 {
            return bad(
                "diagnose.max_steps",
                "must be at least 1 (the number of effects the diagnosis may add)".into(),
            );
        }
        if let Err(e) = self.friction.validate() {
            return bad(&format!("friction.{}", e.key), e.reason);
        }
        Ok(())
    }

    /// `[validation]` checked.
    fn check_validation(&self) -> Result<(), (String, String)> {
        let cutoff = self.fixed_cutoff_hz();
        let v = &self.validation;
        for &f in &v.frequencies_hz {
            if !(f.is_finite() && f > 0.0) {
                return bad(
                    "validation.frequencies_hz",
                    format!("frequencies must be positive, found {f}"),
                );
            }
            if cutoff > 0.0 && f * 2.0 > cutoff {
                return bad(
                    "validation.frequencies_hz",
                    format!(
                        "{f} Hz is too close to the low-pass cut-off signal.cutoff_hz = {cutoff} Hz (keep f ≤ cut-off/2, or set signal.bandwidth = \"auto\" to let the data choose)"
                    ),
                );
            }
        }
        if v.periods < 2 {
            return bad("validation.periods", "simulate at least 2 periods".into());
        }
        if v.pd_grid < 2 && v.pd_random == 0 {
            return bad(
                "validation.pd_grid",
                "the PD check needs points: pd_grid ≥ 2 or pd_random > 0".into(),
            );
        }
        fraction("validation.reversal_reach", v.reversal_reach)?;
        if v.heatmap.iter().any(|&n| !(2..=400).contains(&n)) {
            return bad(
                "validation.heatmap",
                "each resolution must be 2–400 cells".into(),
            );
        }
        Ok(())
    }
}

/// A refusal of the key `k`, with the reason `m`.
fn bad(k: &str, m: String) -> Result<(), (String, String)> {
    Err((k.to_string(), m))
}

/// `v` must be positive and finite.
fn pos(k: &str, v: f64) -> Result<(), (String, String)> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        bad(k, format!("must be a positive finite number, found {v}"))
    }
}

/// `v` must be finite and ≥ 0.
fn nonneg(k: &str, v: f64) -> Result<(), (String, String)> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        bad(k, format!("must be a finite number ≥ 0, found {v}"))
    }
}

/// `v` must be a fraction in (0, 1) of a filter's peak response.
fn fraction(k: &str, v: f64) -> Result<(), (String, String)> {
    if v.is_finite() && v > 0.0 && v < 1.0 {
        Ok(())
    } else {
        bad(
            k,
            format!("must be a fraction in (0, 1) of the filter's peak response, found {v}"),
        )
    }
}

/// Byte offset of a 1-based line and column.
fn offset_of(text: &str, line: usize, column: usize) -> Option<usize> {
    if line == 0 {
        return None;
    }
    let start: usize = text
        .split_inclusive('\n')
        .take(line - 1)
        .map(str::len)
        .sum();
    Some((start + column.saturating_sub(1)).min(text.len()))
}

/// 1-based line and column of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Every key of the document with its dotted path and byte offset, in
/// document order (a light scan, enough to name keys in messages).
pub fn key_positions(text: &str, format: Format) -> Vec<(String, usize)> {
    match format {
        Format::Toml => toml_keys(text),
        Format::Json => json_keys(text),
    }
}

fn toml_keys(text: &str) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    let mut table = String::new();
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let lead = line.len() - line.trim_start().len();
        let l = line.trim();
        if let Some(h) = l.strip_prefix('[') {
            let h = h.trim_start_matches('[');
            if let Some(end) = h.find(']') {
                table = h[..end].trim().replace(' ', "");
                out.push((table.clone(), offset + lead));
            }
        } else if !l.starts_with('#')
            && let Some(eq) = l.find('=')
        {
            let key = l[..eq].trim().trim_matches('"').replace(' ', "");
            if !key.is_empty() {
                let path = if table.is_empty() {
                    key
                } else {
                    format!("{table}.{key}")
                };
                out.push((path, offset + lead));
            }
        }
        offset += line.len();
    }
    out
}

fn json_keys(text: &str) -> Vec<(String, usize)> {
    // Stack of containers: Some(key) for objects (the current key), None
    // for arrays.
    let mut out = Vec::new();
    let mut stack: Vec<Option<String>> = Vec::new();
    let bytes = text.as_bytes();
    let mut i = 0;
    let mut expect_key = false;
    while i < bytes.len() {
        match bytes[i] {
            b'{' => {
                stack.push(Some(String::new()));
                expect_key = true;
            }
            b'[' => {
                stack.push(None);
                expect_key = false;
            }
            b'}' | b']' => {
                stack.pop();
                expect_key = false;
            }
            b',' => expect_key = matches!(stack.last(), Some(Some(_))),
            b'"' => {
                let start = i;
                i += 1;
                let mut s = String::new();
                while i < bytes.len() && bytes[i] != b'"' {
                    if bytes[i] == b'\\' {
                        i += 1;
                    }
                    if i < bytes.len() {
                        s.push(bytes[i] as char);
                    }
                    i += 1;
                }
                if expect_key {
                    if let Some(Some(k)) = stack.last_mut() {
                        *k = s;
                    }
                    let path: Vec<&str> = stack.iter().flatten().map(String::as_str).collect();
                    out.push((path.join("."), start));
                    expect_key = false;
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_round_trip_through_toml() {
        let c = Config::default();
        let text = c.to_toml();
        let back = Config::parse(&text, Format::Toml, "d.toml").unwrap();
        assert_eq!(back, c);
    }

    #[test]
    fn key_paths_in_both_formats() {
        let t = "# c\n[signal]\ncutoff_hz = 5\n[identification.sdp]\nepsilon = 1\n";
        let k = toml_keys(t);
        assert!(k.iter().any(|(p, _)| p == "signal.cutoff_hz"));
        assert!(k.iter().any(|(p, _)| p == "identification.sdp.epsilon"));
        let j = r#"{"signal": {"cutoff_hz": 5, "x": [1, {"a": 2}]}, "robot": {}}"#;
        let k = json_keys(j);
        let names: Vec<&str> = k.iter().map(|(p, _)| p.as_str()).collect();
        assert_eq!(
            names,
            [
                "signal",
                "signal.cutoff_hz",
                "signal.x",
                "signal.x.a",
                "robot"
            ]
        );
    }
}
