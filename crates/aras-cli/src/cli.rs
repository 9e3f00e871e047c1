//! The command line (`clap`): one subcommand per tool, each in its own
//! module under [`crate::cmd`]. To add a tool, add a variant here and a
//! module there.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

/// ARAS-Diamond dynamics toolkit: excitation design, simulation,
/// identification, validation and prediction (docs/model.md).
#[derive(Debug, Parser)]
#[command(name = "aras", version, about, long_about = None)]
pub struct Cli {
    /// The tool to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The tools.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// The whole mission on the (simulated) robot: design → simulate →
    /// process → identify (OLS + SDP) → validate → report.
    Pipeline(PipelineArgs),
    /// Design an optimal excitation trajectory ((74)–(77), `docs/excitation.md`) → trajectory.json.
    Excite(ExciteArgs),
    /// Simulate the robot tracking a trajectory → LOG.csv + LOG.json.
    Simulate(SimulateArgs),
    /// Identify the dynamic parameters from a log → params.json, robot.xml (MJCF), base.json, report.
    Identify(IdentifyArgs),
    /// Validate a parameter file: cross-validation on (79), workspace PD check.
    Validate(ValidateArgs),
    /// Predict torques of a log with a parameter file → PRED.csv (t,tau1,tau2).
    Predict(PredictArgs),
    /// Find where model and measurement disagree, name the missing effect,
    /// add it and show the gap shrink → diagnosis.{md,html,json}.
    Diagnose(DiagnoseArgs),
    /// Write the robot of a parameter file as a MuJoCo model (MJCF):
    /// bodies, joints, the loop constraint, friction and actuators (docs/mjcf.md).
    ExportMjcf(ExportMjcfArgs),
    /// Friction of one joint of any robot from its log: classical and
    /// dynamic models, then the diagnosis of what they miss →
    /// `friction.json`, `report.html`, `pred_<log>.csv` (docs/friction.md).
    Friction(FrictionArgs),
    /// Apply a fitted friction model (`friction.json`) to a new log of the
    /// joint → PRED.csv (t,tau), without refitting (docs/friction.md).
    FrictionPredict(FrictionPredictArgs),
}

/// `aras export-mjcf`.
#[derive(Debug, Args)]
pub struct ExportMjcfArgs {
    /// Parameter file (e.g. params.json from identify: physically consistent).
    #[arg(long, value_name = "P.json")]
    pub params: PathBuf,
    /// Output MJCF file.
    #[arg(long, default_value = "robot.xml", value_name = "robot.xml")]
    pub out: PathBuf,
    /// Shared options.
    #[command(flatten)]
    pub common: Common,
}

/// `aras friction`.
#[derive(Debug, Args)]
pub struct FrictionArgs {
    /// The training log: CSV with a header and columns t (s), q (rad),
    /// dq (rad/s, computed from q when absent), tau (N·m, the friction
    /// torque), optional ddq (rad/s²); other columns are ignored. Or a ROS
    /// 2 bag (.mcap): one joint of its JointState messages (`--joint`).
    #[arg(long, value_name = "TRAIN.csv|BAG.mcap")]
    pub data: PathBuf,
    /// A validation log, same format (repeat for several): it scores the
    /// models and takes part in the diagnosis's choices.
    #[arg(long, value_name = "VAL.csv")]
    pub validate: Vec<PathBuf>,
    /// A log to predict with the final model, same format (repeat for
    /// several): applied after every choice is made, never used for one;
    /// writes `pred_<log>.csv` (its `tau` column is only compared with the
    /// prediction).
    #[arg(long, value_name = "LOG.csv")]
    pub predict: Vec<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "out-friction", value_name = "DIR")]
    pub out: PathBuf,
    /// How the joint logs are read.
    #[command(flatten)]
    pub log: JointLogArgs,
    /// Hold the Stribeck shape exponent δ of the Stribeck and LuGre models
    /// at this value (2 is the classical LuGre shape) instead of fitting it
    /// (overrides the config's `friction.fit.shape`).
    #[arg(long, value_name = "DELTA", value_parser = positive, allow_hyphen_values = true)]
    pub shape: Option<f64>,
    /// `--config` (its `[friction]` section holds the analysis settings),
    /// `--force`, `--quiet`.
    #[command(flatten)]
    pub common: Common,
}

/// How a joint log is read: a CSV's column names, or a ROS 2 bag's topic,
/// joint and time stamps.
#[derive(Debug, Args)]
pub struct JointLogArgs {
    /// Your column names, e.g. `t=time,q=q2,dq=dq2,tau=tau_f` (roles: t, q,
    /// dq, tau, ddq, load; roles not given keep their default names).
    #[arg(long, value_name = "ROLE=NAME,…")]
    pub columns: Option<String>,
    /// ROS 2 bag (.mcap) only: the sensor_msgs/msg/JointState topic (needed
    /// when the bag has several).
    #[arg(long, value_name = "TOPIC")]
    pub topic: Option<String>,
    /// ROS 2 bag only: the joint to analyse, by name (default: the only
    /// joint of a one-joint topic); its position is q, velocity dq, effort tau.
    #[arg(long, value_name = "NAME")]
    pub joint: Option<String>,
    /// ROS 2 bag only: the samples' time, `header` (header.stamp) or `log`
    /// (the bag's receive time).
    #[arg(long, value_enum, default_value = "header")]
    pub stamps: StampsArg,
}

/// `aras friction-predict`.
#[derive(Debug, Args)]
pub struct FrictionPredictArgs {
    /// The model: `friction.json` written by `aras friction` (its final
    /// model: the best classical model plus the effects it added).
    #[arg(long, value_name = "friction.json")]
    pub model: PathBuf,
    /// The log to predict, in `aras friction`'s format; its `tau` column is
    /// only compared with the prediction (RMS and fitness (78) printed).
    #[arg(long, value_name = "LOG.csv|BAG.mcap")]
    pub data: PathBuf,
    /// Output CSV (`t,tau`).
    #[arg(long, default_value = "pred.csv", value_name = "PRED.csv")]
    pub out: PathBuf,
    /// How the joint log is read.
    #[command(flatten)]
    pub log: JointLogArgs,
    /// Replace an existing output file, only if aras wrote it.
    #[arg(long)]
    pub force: bool,
}

/// `aras diagnose`.
#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// A serial or tree robot from its URDF (docs/urdf.md) in place of
    /// ARAS-Diamond: its candidates are Stribeck friction, an
    /// offset and a spring per joint, and a torque delay (docs/urdf.md, Diagnose).
    #[arg(long, value_name = "R.urdf")]
    pub urdf: Option<PathBuf>,
    /// The training log (docs/log-format.md), e.g. the designed excitation.
    #[arg(long, value_name = "TRAIN.csv")]
    pub data: PathBuf,
    /// A validation log (repeat for several; at least one). Each is read
    /// with its own sidecar (VAL.json), if present.
    #[arg(long, value_name = "VAL.csv", required = true)]
    pub validate: Vec<PathBuf>,
    /// The training log's period and sidecar.
    #[command(flatten)]
    pub log: LogArgs,
    /// Process the logs in bounded memory (docs/scale.md): with a period,
    /// a log's average is summed while reading; otherwise it is processed
    /// in overlapping blocks into a scratch file in the output's staging
    /// directory, which the diagnosis reads window by window. `auto` does
    /// so for each log larger than 64 MB, `on` for every log, `off` never.
    #[arg(long, value_enum, default_value = "auto")]
    pub streaming: StreamingMode,
    /// Output directory.
    #[arg(long, default_value = "out-diagnose", value_name = "DIR")]
    pub out: PathBuf,
    /// Shared options.
    #[command(flatten)]
    pub common: Common,
}

/// Where a log's period and metadata come from: the same flags for
/// `identify`, `predict` and `diagnose`, so they process a log alike.
#[derive(Debug, Clone, Default, Args)]
pub struct LogArgs {
    /// Period (s) of the motion, for period averaging or the harmonic fit
    /// (default: the sidecar's `excitation.period_s`, else detected from the
    /// angles).
    #[arg(long, value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub period: Option<f64>,
    /// Sidecar file, or `none` to read no sidecar (default: LOG.json next
    /// to the log, if it declares `"format": "aras-log/1"`; a file of that
    /// name without the declaration is not read, with a note).
    #[arg(long, value_name = "JSON|none")]
    pub sidecar: Option<PathBuf>,
    /// Your column names, e.g. `t=time,theta1=q1,theta2=q2,tau1=torque_a,tau2=torque_b`
    /// (roles: t, theta1, theta2, tau1, tau2, i1, i2, enc1, enc2, dtheta1,
    /// dtheta2, ddtheta1, ddtheta2; roles not given keep their standard
    /// names; docs/log-format.md).
    #[arg(long, value_name = "ROLE=NAME,…")]
    pub columns: Option<String>,
    /// ROS 2 bag (.mcap) only: the sensor_msgs/msg/JointState topic to read
    /// (needed when the bag has several).
    #[arg(long, value_name = "TOPIC")]
    pub topic: Option<String>,
    /// ROS 2 bag only: which joints are θ1 and θ2, e.g.
    /// `theta1=motor_left,theta2=motor_right` (default: the two joints of a
    /// two-joint message, in its order).
    #[arg(long, value_name = "theta1=JOINT,theta2=JOINT")]
    pub joints: Option<String>,
    /// ROS 2 bag only: the samples' time, `header` (header.stamp) or `log`
    /// (the bag's receive time, for drivers that leave the stamp unset).
    #[arg(long, value_enum, default_value = "header")]
    pub stamps: StampsArg,
    /// Unit of the log's `t` column (default: seconds, and a whole-number
    /// step below 10 Hz is refused as probably not seconds; config
    /// `log.time_unit`).
    #[arg(long, value_enum, value_name = "UNIT")]
    pub time_unit: Option<TimeUnitArg>,
    /// What to do with isolated glitches, samples far off their neighbours
    /// (default `warn`, naming their lines; config `log.glitches`).
    #[arg(long, value_enum, value_name = "ACTION")]
    pub glitches: Option<GlitchArg>,
    /// Resample a jittered or gappy log onto a uniform grid at its nominal
    /// step before processing; every gap is reported (config `log.resample`).
    #[arg(long)]
    pub resample: bool,
    /// Longest gap (s) `--resample` interpolates across; longer gaps refuse
    /// the log (default 0.005; config `log.max_gap_s`).
    #[arg(long, value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub max_gap: Option<f64>,
    /// What the logged torques are: `sampled` (measured at each sample's
    /// time, like the angles) or `held` (commands held until the next
    /// sample, as a simulator or a drive's command log writes them).
    /// Default: the sidecar's `torques`, else sampled (config
    /// `log.torques`); a value contradicting the sidecar is refused.
    #[arg(long, value_enum, value_name = "TIMING")]
    pub torques: Option<TorquesArg>,
}

/// `--torques`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TorquesArg {
    /// Measured at the sample times.
    Sampled,
    /// Held over each sample step (zero-order hold).
    Held,
}

impl From<TorquesArg> for aras_log::TorqueTiming {
    fn from(t: TorquesArg) -> Self {
        match t {
            TorquesArg::Sampled => Self::Sampled,
            TorquesArg::Held => Self::Held,
        }
    }
}

/// `--stamps`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum StampsArg {
    /// header.stamp of each message.
    #[default]
    Header,
    /// The bag's log time.
    Log,
}

/// `--time-unit`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TimeUnitArg {
    /// Seconds.
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
    /// Nanoseconds.
    Ns,
}

impl From<TimeUnitArg> for aras_log::TimeUnit {
    fn from(u: TimeUnitArg) -> Self {
        match u {
            TimeUnitArg::S => Self::Seconds,
            TimeUnitArg::Ms => Self::Milliseconds,
            TimeUnitArg::Us => Self::Microseconds,
            TimeUnitArg::Ns => Self::Nanoseconds,
        }
    }
}

/// `--glitches`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum GlitchArg {
    /// Refuse the log, naming each glitch's line and column.
    Refuse,
    /// Keep the samples, with a warning.
    Warn,
    /// Remove their rows (the gaps are interpolated).
    Drop,
    /// Replace each by the interpolation of its neighbours, with a warning.
    Repair,
    /// Do not look for glitches.
    Off,
}

impl From<GlitchArg> for aras_log::GlitchAction {
    fn from(g: GlitchArg) -> Self {
        match g {
            GlitchArg::Refuse => Self::Refuse,
            GlitchArg::Warn => Self::Warn,
            GlitchArg::Drop => Self::Drop,
            GlitchArg::Repair => Self::Repair,
            GlitchArg::Off => Self::Off,
        }
    }
}

impl LogArgs {
    /// True if `--sidecar none`.
    fn no_sidecar(&self) -> bool {
        self.sidecar.as_deref() == Some(std::path::Path::new("none"))
    }

    /// The config's `[log]` section with this command line's overrides.
    pub fn settings(&self, cfg: &crate::config::LogConfig) -> crate::config::LogConfig {
        let mut s = cfg.clone();
        if let Some(u) = self.time_unit {
            s.time_unit = Some(u.into());
        }
        if let Some(g) = self.glitches {
            s.glitches = g.into();
        }
        s.resample |= self.resample;
        if let Some(m) = self.max_gap {
            s.max_gap_s = m;
        }
        if let Some(t) = self.torques {
            s.torques = Some(t.into());
        }
        s
    }

    /// The sidecar file `log` may be read with, which outputs must never
    /// replace: `--sidecar FILE`, else LOG.json beside it (with `--sidecar
    /// none` too: it is still the lab's file).
    pub fn sidecar_of(&self, log: &std::path::Path) -> PathBuf {
        match &self.sidecar {
            Some(p) if !self.no_sidecar() => p.clone(),
            _ => aras_log::sidecar_path(log),
        }
    }

    /// The log reader's options: `--sidecar`, `--columns`, the time unit,
    /// the torque timing,
    /// for bags `--topic`, `--joints`, `--stamps`, and, with resampling,
    /// gaps let through to the resampler (which judges them against
    /// `max_gap_s`).
    pub fn read_options(
        &self,
        cfg: &crate::config::LogConfig,
    ) -> anyhow::Result<aras_log::ReadOptions> {
        use anyhow::Context;
        use aras_log::{BagOptions, ColumnNames, JointNames, ReadOptions, SidecarSource, Stamps};
        let s = self.settings(cfg);
        let defaults = ReadOptions::default();
        Ok(ReadOptions {
            // ARAS-Diamond's two joints: columns of others are ignored.
            joints: Some(2),
            time_unit: s.time_unit,
            torques: s.torques,
            step_tolerance: if s.resample {
                RESAMPLE_STEP_TOLERANCE
            } else {
                defaults.step_tolerance
            },
            sidecar: if self.no_sidecar() {
                SidecarSource::None
            } else {
                self.sidecar
                    .as_ref()
                    .map_or(SidecarSource::Auto, |p| SidecarSource::Path(p.clone()))
            },
            columns: match &self.columns {
                Some(spec) => ColumnNames::parse(spec).context("option --columns")?,
                None => ColumnNames::default(),
            },
            bag: BagOptions {
                topic: self.topic.clone(),
                joints: match &self.joints {
                    Some(spec) => {
                        let names = JointNames::parse(spec).context("option --joints")?;
                        if names.names.len() != 2 {
                            anyhow::bail!(
                                "option --joints: `{spec}` names {} joint(s) but ARAS-Diamond \
                                 has two: give both theta1=JOINT and theta2=JOINT",
                                names.names.len()
                            );
                        }
                        names
                    }
                    None => JointNames::default(),
                },
                stamps: match self.stamps {
                    StampsArg::Header => Stamps::Header,
                    StampsArg::Log => Stamps::Log,
                },
            },
            ..defaults
        })
    }
}

/// The reader's step tolerance when resampling: any step passes the reader
/// and the resampler refuses gaps beyond `log.max_gap_s`.
const RESAMPLE_STEP_TOLERANCE: f64 = 1e12;

/// Options every command shares.
#[derive(Debug, Clone, Args)]
pub struct Common {
    /// Configuration file (.toml or .json; docs/config.md). Defaults apply
    /// to every key not given.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Replace an existing output, only if aras wrote it: a directory whose
    /// files are all listed in its `.aras-manifest.json`, or a file of the
    /// same kind. A directory holding an input or anything else is refused.
    #[arg(long)]
    pub force: bool,
    /// No progress display and no stage lines on stderr.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `aras pipeline`.
#[derive(Debug, Args)]
pub struct PipelineArgs {
    /// Output directory.
    #[arg(long, default_value = "out", value_name = "DIR")]
    pub out: PathBuf,
    /// Seed of the design and of the sensor noise (overrides the config's
    /// `trajectory.seed` and `simulation.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Leave wall-clock timings out of summary.json, so the same seed gives
    /// byte-identical outputs (the report still shows them).
    #[arg(long)]
    pub reproducible: bool,
    /// Print the configuration (TOML) and exit: the defaults, or with
    /// --config that file's settings with the defaults filled in.
    #[arg(long)]
    pub print_config: bool,
    /// Shared options.
    #[command(flatten)]
    pub common: Common,
}

/// `aras excite`.
#[derive(Debug, Args)]
pub struct ExciteArgs {
    /// A serial or tree robot from its URDF (docs/urdf.md) in place of
    /// ARAS-Diamond: designed within its joint position and velocity
    /// limits (10 % margin, 10 rad/s², 10 s period, 5 harmonics).
    #[arg(long, value_name = "R.urdf")]
    pub urdf: Option<PathBuf>,
    /// Output trajectory file.
    #[arg(long, default_value = "trajectory.json", value_name = "FILE")]
    pub out: PathBuf,
    /// Seed of the design's starts (overrides `trajectory.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Shared options.
    #[command(flatten)]
    pub common: Common,
}

/// `aras simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// A serial or tree robot from its URDF (docs/urdf.md) in place of
    /// ARAS-Diamond: its URDF inertials with typical drives
    /// (docs/urdf.md, Simulator) tracking --trajectory under PD control at 1 kHz.
    #[arg(long, value_name = "R.urdf")]
    pub urdf: Option<PathBuf>,
    /// With --urdf: recorded seconds (default 60).
    #[arg(long, value_name = "S", value_parser = positive, allow_hyphen_values = true, requires = "urdf")]
    pub duration: Option<f64>,
    /// With --urdf: an effect the simulated robot has and the model lacks,
    /// `stribeck:J:LEVEL:V_S` (N·m above Coulomb, rad/s) or
    /// `cubic_spring:J:K3[:Q0]` on joint J (1-based); repeat for several.
    #[arg(long, value_name = "EFFECT", requires = "urdf")]
    pub hidden: Vec<String>,
    /// Trajectory file from `aras excite` (periodic: `simulation.periods` periods).
    #[arg(long, value_name = "FILE", conflicts_with = "frequency")]
    pub trajectory: Option<PathBuf>,
    /// Instead: the paper's validation trajectory (79) at this frequency (Hz).
    #[arg(long, value_name = "HZ", value_parser = positive, allow_hyphen_values = true)]
    pub frequency: Option<f64>,
    /// Output log (the sidecar goes next to it as .json).
    #[arg(long, default_value = "log.csv", value_name = "LOG.csv")]
    pub out: PathBuf,
    /// Noise seed (overrides `simulation.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Shared options.
    #[command(flatten)]
    pub common: Common,
}

/// `aras identify`.
#[derive(Debug, Args)]
pub struct IdentifyArgs {
    /// The log (docs/log-format.md): a CSV, or a ROS 2 bag (.mcap) of
    /// sensor_msgs/msg/JointState.
    #[arg(long, value_name = "LOG.csv|BAG.mcap")]
    pub data: PathBuf,
    /// A serial or tree robot from its URDF (docs/urdf.md), identified in
    /// place of ARAS-Diamond: writes params.json (`aras-urdf-params/1`),
    /// robot_identified.urdf (its inertials identified, every other byte
    /// kept) and robot.xml (MJCF). The log holds one angle and torque
    /// column per movable joint, in the URDF's joint order.
    #[arg(long, value_name = "R.urdf")]
    pub urdf: Option<PathBuf>,
    /// The log's period and sidecar.
    #[command(flatten)]
    pub log: LogArgs,
    /// Extra effects to identify with the paper's model, comma-separated, as
    /// `diagnose` names them: torque_offset, coulomb_asymmetry,
    /// `stribeck_friction[:V_S]`, passive_joint_viscous, `cogging:CYCLES[:ORDER]`,
    /// quadratic_damping, and `time_delay:D` (the torque taken D samples after
    /// the angles, fractions interpolated). With `--urdf`:
    /// `stribeck_friction:JOINT:V_S`, the Stribeck column the diagnosis
    /// names on a joint, at its refined `v_s` (rad/s).
    #[arg(long, value_name = "ID[:ARG],…", value_delimiter = ',')]
    pub effects: Vec<String>,
    /// Output directory.
    #[arg(long, default_value = "out-identify", value_name = "DIR")]
    pub out: PathBuf,
    /// Leave wall-clock timings out of summary.json.
    #[arg(long)]
    pub reproducible: bool,
    /// Streaming identification in bounded memory (docs/scale.md): `auto`
    /// streams logs larger than 256 MB, `on` always, `off` never.
    #[arg(long, value_enum, default_value = "auto")]
    pub streaming: StreamingMode,
    /// How streaming accumulates the least squares: `gram` (normal
    /// equations, fast, accuracy-checked; falls back to `qr` when the check
    /// fails) or `qr` (incremental QR).
    #[arg(long, value_enum, default_value = "gram")]
    pub accumulation: AccumulationArg,
    /// Shared options.
    #[command(flatten)]
    pub common: Common,
}

/// `identify --streaming`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum StreamingMode {
    /// Stream logs larger than the command's threshold (its --streaming
    /// help gives it).
    Auto,
    /// Always stream.
    On,
    /// Never stream (the whole log in memory).
    Off,
}

/// `identify --accumulation`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AccumulationArg {
    /// Normal equations.
    Gram,
    /// Incremental QR.
    Qr,
}

/// `aras validate`.
#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// A serial or tree robot from its URDF (docs/urdf.md) in place of
    /// ARAS-Diamond: --params (its `identify --urdf` params.json)
    /// predicts each --data log, scored with (78) against its raw torques on
    /// every row.
    #[arg(long, value_name = "R.urdf")]
    pub urdf: Option<PathBuf>,
    /// With --urdf: a validation log (repeat for several).
    #[arg(long, value_name = "VAL.csv", requires = "urdf")]
    pub data: Vec<PathBuf>,
    /// Parameter file to validate (e.g. params.json from identify).
    #[arg(long, value_name = "P.json")]
    pub params: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "out-validate", value_name = "DIR")]
    pub out: PathBuf,
    /// Shared options.
    #[command(flatten)]
    pub common: Common,
}

/// `aras predict`.
#[derive(Debug, Args)]
pub struct PredictArgs {
    /// A serial or tree robot from its URDF (docs/urdf.md) in place of
    /// ARAS-Diamond: --params is its `identify --urdf` params.json,
    /// and PRED.csv has one torque column per joint.
    #[arg(long, value_name = "R.urdf")]
    pub urdf: Option<PathBuf>,
    /// Parameter file.
    #[arg(long, value_name = "P.json")]
    pub params: PathBuf,
    /// The log whose angles drive the prediction.
    #[arg(long, value_name = "LOG.csv")]
    pub data: PathBuf,
    /// Output CSV with columns t,tau1,tau2.
    #[arg(long, value_name = "PRED.csv")]
    pub out: PathBuf,
    /// Also write the figures as JSON (`"format": "aras-predict/1"`: the
    /// route of PRED.csv, its fitness (78), the processing loss).
    #[arg(long, value_name = "PRED.json")]
    pub summary: Option<PathBuf>,
    /// The log's period and sidecar (every row of the log is predicted
    /// either way).
    #[command(flatten)]
    pub log: LogArgs,
    /// Shared options.
    #[command(flatten)]
    pub common: Common,
}

/// Parser of a strictly positive, finite number (periods, frequencies).
/// Negative values are parsed rather than taken for options
/// (`allow_hyphen_values`), so the message says what is wrong with them.
fn positive(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number; give a positive number such as 10"))?;
    if !v.is_finite() || v <= 0.0 {
        return Err(format!(
            "{v} is not a positive finite number; give a positive value such as 10"
        ));
    }
    Ok(v)
}
