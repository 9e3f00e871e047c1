//! ROS 2 bags as logs: the `sensor_msgs/msg/JointState` messages of one
//! topic of an MCAP file (`docs/log-format.md`, "ROS 2 bags").
//!
//! The MCAP container (chunks, zstd or lz4 compression, channels, schemas)
//! is read by the `mcap` crate; the messages' CDR serialisation is decoded
//! here: a `JointState` is a fixed, small layout (header stamp, frame id,
//! four sequences), and decoding it directly gives exact messages about
//! which message and which field is wrong.

#![cfg_attr(not(feature = "bags"), allow(dead_code))]

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::LogError;
use crate::reader::Columns;

/// The message type read from a bag.
pub const JOINT_STATE: &str = "sensor_msgs/msg/JointState";

/// The first bytes of every MCAP file.
pub const MCAP_MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// Which time a bag's samples take.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stamps {
    /// `header.stamp` of each message: when the driver sampled the joints.
    #[default]
    Header,
    /// The bag's log time: when the recorder received the message (for
    /// drivers that leave `header.stamp` unset; includes transport jitter).
    Log,
}

/// Which joints of the `JointState` messages are θ1, θ2, …, in order. All
/// or none: with none, the joints of the first message in its order (as
/// many as [`ReadOptions::joints`](crate::ReadOptions::joints) says, if it
/// says).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct JointNames {
    /// Joint names of θ1, θ2, … (their efforts are τ1, τ2, …).
    pub names: Vec<String>,
}

impl JointNames {
    /// Parses `theta1=NAME,theta2=NAME,…` (joint names are matched exactly,
    /// as ROS names are case-sensitive; every role from `theta1` up to the
    /// highest given).
    pub fn parse(spec: &str) -> Result<Self, LogError> {
        let bad = |reason: String| LogError::InvalidOption {
            name: "joints",
            value: spec.into(),
            reason,
        };
        let mut given: Vec<Option<String>> = Vec::new();
        for item in spec.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let Some((role, name)) = item.split_once('=') else {
                return Err(bad(format!(
                    "`{item}` is not ROLE=JOINT: write theta1=JOINT,theta2=JOINT,…"
                )));
            };
            let (role, name) = (role.trim(), name.trim());
            if name.is_empty() {
                return Err(bad(format!("role `{role}` has an empty joint name")));
            }
            let lower = role.to_ascii_lowercase();
            let Some(crate::header::Field::Joint(crate::header::Role::Theta, j)) =
                crate::header::Field::parse(&lower)
            else {
                return Err(bad(format!(
                    "unknown role `{lower}`: the roles are theta1, theta2, …"
                )));
            };
            if given.len() <= j {
                given.resize(j + 1, None);
            }
            if given[j].is_some() {
                return Err(bad(format!("role `{role}` is given twice")));
            }
            if let Some(k) = given.iter().position(|g| g.as_deref() == Some(name)) {
                return Err(bad(format!(
                    "theta{} and theta{} are both joint `{name}`: give different joints",
                    k + 1,
                    j + 1
                )));
            }
            given[j] = Some(name.to_string());
        }
        if let Some(j) = given.iter().position(Option::is_none) {
            return Err(bad(format!(
                "theta{} is not given: name every joint from theta1 to theta{}, or none",
                j + 1,
                given.len()
            )));
        }
        Ok(Self {
            names: given.into_iter().flatten().collect(),
        })
    }

    /// True if no joint is named (the first message's joints apply).
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }
}

/// How a ROS 2 bag is read. `Default`: the only `JointState` topic, the
/// first message's joints in its order, header stamps.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BagOptions {
    /// The `JointState` topic to read (needed when the bag has several).
    pub topic: Option<String>,
    /// Which joints are θ1, θ2, ….
    pub joints: JointNames,
    /// Which time the samples take.
    pub stamps: Stamps,
}

impl BagOptions {
    /// True if every option has its default.
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// True if `path` is a ROS 2 bag: extension `.mcap`, or a file that starts
/// with the MCAP magic bytes.
pub fn is_bag(path: &Path) -> bool {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
    {
        return true;
    }
    use std::io::Read;
    let mut magic = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .is_ok_and(|()| &magic == MCAP_MAGIC)
}

/// One topic of a bag, decoded into log rows.
pub(crate) struct BagRows {
    /// Rows (`theta_dot` filled if every message has the joints' velocity).
    pub cols: Columns,
    /// True if `cols.theta_dot` holds the messages' velocities.
    pub has_velocity: bool,
    /// The topic read.
    pub topic: String,
    /// What was read and how (topic, joints, times, rates).
    pub notes: Vec<String>,
}

/// A decoded `JointState`, borrowing its strings from the message.
#[derive(Default)]
struct JointState<'a> {
    sec: i32,
    nanosec: u32,
    names: Vec<&'a str>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
}

/// A CDR (XCDR1, as ROS 2 writes it) cursor over one message.
struct Cdr<'a> {
    /// The bytes after the 4-byte encapsulation header (alignment origin).
    buf: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> Cdr<'a> {
    fn new(data: &'a [u8]) -> Result<Self, String> {
        if data.len() < 4 {
            return Err(format!(
                "the message has {} bytes, fewer than its 4-byte CDR header",
                data.len()
            ));
        }
        let little = match (data[0], data[1]) {
            (0, 0) => false,
            (0, 1) => true,
            (a, b) => {
                return Err(format!(
                    "CDR encapsulation 0x{a:02x}{b:02x} is not plain CDR (0x0000 or 0x0001, \
                     what ROS 2 writes)"
                ));
            }
        };
        Ok(Self {
            buf: &data[4..],
            pos: 0,
            little,
        })
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.buf.len());
        let Some(end) = end else {
            return Err(format!(
                "the message ends inside {what} (byte {} of {}): it is truncated or not a \
                 {JOINT_STATE}",
                self.pos + 4,
                self.buf.len() + 4
            ));
        };
        let s = &self.buf[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn align(&mut self, n: usize) {
        self.pos = self.pos.div_ceil(n) * n;
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        self.align(4);
        let b: [u8; 4] = self.take(4, what)?.try_into().expect("4 bytes");
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn f64(&mut self, what: &str) -> Result<f64, String> {
        self.align(8);
        let b: [u8; 8] = self.take(8, what)?.try_into().expect("8 bytes");
        Ok(if self.little {
            f64::from_le_bytes(b)
        } else {
            f64::from_be_bytes(b)
        })
    }

    fn string(&mut self, what: &str) -> Result<&'a str, String> {
        let n = self.u32(what)? as usize;
        let bytes = self.take(n, what)?;
        let bytes = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        std::str::from_utf8(bytes).map_err(|_| format!("{what} is not UTF-8 text"))
    }

    /// A sequence length, checked against the bytes left (`min` bytes per
    /// element), so a corrupt length cannot ask for a huge allocation.
    fn len(&mut self, what: &str, min: usize) -> Result<usize, String> {
        let n = self.u32(what)? as usize;
        if n.saturating_mul(min) > self.buf.len() - self.pos.min(self.buf.len()) {
            return Err(format!(
                "{what} claims {n} elements, more than the message holds: it is truncated or \
                 not a {JOINT_STATE}"
            ));
        }
        Ok(n)
    }

    fn f64s(&mut self, what: &str, out: &mut Vec<f64>) -> Result<(), String> {
        let n = self.len(what, 8)?;
        out.clear();
        for _ in 0..n {
            out.push(self.f64(what)?);
        }
        Ok(())
    }
}

/// Decodes one CDR `sensor_msgs/msg/JointState` into `m`.
fn decode<'a>(data: &'a [u8], m: &mut JointState<'a>) -> Result<(), String> {
    let mut c = Cdr::new(data)?;
    m.sec = c.u32("header.stamp.sec")? as i32;
    m.nanosec = c.u32("header.stamp.nanosec")?;
    c.string("header.frame_id")?;
    let n = c.len("name", 4)?;
    m.names.clear();
    for _ in 0..n {
        m.names.push(c.string("name")?);
    }
    c.f64s("position", &mut m.position)?;
    c.f64s("velocity", &mut m.velocity)?;
    c.f64s("effort", &mut m.effort)
}

/// A topic of the bag: its message type and how many messages it has.
struct TopicInfo {
    schema: String,
    encoding: String,
    messages: usize,
}

fn topic_list(topics: &BTreeMap<String, TopicInfo>, only_joint_states: bool) -> String {
    let list: Vec<String> = topics
        .iter()
        .filter(|(_, i)| !only_joint_states || i.schema == JOINT_STATE)
        .map(|(t, i)| format!("{t} ({} {} messages)", i.messages, i.schema))
        .collect();
    if list.is_empty() {
        "none".into()
    } else {
        list.join(", ")
    }
}

fn ms(ns: i64) -> String {
    format!("{}", crate::error::sig(ns as f64 * 1e-6))
}

/// Which joints a reading takes.
pub(crate) struct Wanted<'a> {
    /// The role of the `k`-th joint, for messages (`θ1`, `θ2`; `q`).
    pub role: &'a dyn Fn(usize) -> String,
    /// Their names; `None`: the first message's joints, if it names exactly
    /// [`count`](Self::count).
    pub names: Option<Vec<String>>,
    /// How many joints when no names are given (`None`: as many as the
    /// first message names).
    pub count: Option<usize>,
    /// "are θ1, θ2, …", for messages.
    pub which: &'a str,
    /// The option that names them, with its form.
    pub flag: &'a str,
}

/// The chosen joints of a topic's messages, one vector per joint.
pub(crate) struct JointRows {
    pub t: Vec<f64>,
    pub position: Vec<Vec<f64>>,
    /// If every message has the joints' velocity.
    pub velocity: Option<Vec<Vec<f64>>>,
    pub effort: Vec<Vec<f64>>,
    pub topic: String,
    /// The joints' names.
    pub joints: Vec<String>,
    pub notes: Vec<String>,
}

#[cfg(feature = "bags")]
/// Reads the log joints of the MCAP file `bytes` into log rows (`joints`
/// of them if given, as [`ReadOptions::joints`](crate::ReadOptions::joints));
/// `file` names it in messages.
pub(crate) fn read(
    bytes: &[u8],
    file: &str,
    opts: &BagOptions,
    joints: Option<usize>,
) -> Result<BagRows, LogError> {
    if let Some(n) = joints
        && !opts.joints.is_empty()
        && opts.joints.names.len() != n
    {
        return Err(LogError::InvalidOption {
            name: "joints",
            value: opts.joints.names.join(","),
            reason: format!(
                "{} joints are named but the robot has {n}: name one per joint",
                opts.joints.names.len()
            ),
        });
    }
    let role = |k: usize| format!("θ{}", k + 1);
    let which = match joints {
        Some(1) => "is θ1".to_string(),
        Some(2) => "are θ1 and θ2".to_string(),
        Some(n) => format!("are θ1 … θ{n}"),
        None => "are θ1, θ2, …".to_string(),
    };
    let wanted = Wanted {
        role: &role,
        names: (!opts.joints.is_empty()).then(|| opts.joints.names.clone()),
        count: joints,
        which: &which,
        flag: "--joints theta1=JOINT,theta2=JOINT,… (BagOptions::joints)",
    };
    let r = read_joints(bytes, file, opts.topic.as_deref(), opts.stamps, wanted)?;
    let has_velocity = r.velocity.is_some();
    let n = r.position.len();
    Ok(BagRows {
        cols: Columns {
            t: r.t,
            theta: r.position,
            tau: r.effort,
            theta_dot: r.velocity.unwrap_or_else(|| vec![Vec::new(); n]),
            theta_ddot: vec![Vec::new(); n],
        },
        has_velocity,
        topic: r.topic,
        notes: r.notes,
    })
}

/// One joint of a ROS 2 bag's `JointState` topic ([`read_bag_joint`]).
#[derive(Debug, Clone, PartialEq)]
pub struct JointSamples {
    /// `BAG#TOPIC`: the file and topic, for messages.
    pub label: String,
    /// The joint's name.
    pub joint: String,
    /// Time (s) from the first message (header stamps or log time).
    pub t: Vec<f64>,
    /// Position (rad).
    pub position: Vec<f64>,
    /// Velocity (rad/s), if every message has it.
    pub velocity: Option<Vec<f64>>,
    /// Effort (N·m).
    pub effort: Vec<f64>,
    /// What was read and how (topic, joint, times, rates).
    pub notes: Vec<String>,
}

/// Reads one joint of a ROS 2 bag (for single-joint tools such as the
/// friction analysis): `topic` as [`BagOptions::topic`], `joint` by name
/// (`None`: the only joint of a one-joint topic). The same checks as a log's
/// bag reading apply, except the sampling checks, which belong to the user
/// of the samples.
#[cfg(feature = "bags")]
pub fn read_bag_joint(
    path: &Path,
    topic: Option<&str>,
    joint: Option<&str>,
    stamps: Stamps,
) -> Result<JointSamples, LogError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| LogError::Io {
        file: file.clone(),
        source,
    })?;
    let role = |_: usize| "q".to_string();
    let wanted = Wanted {
        role: &role,
        names: joint.map(|j| vec![j.to_string()]),
        count: Some(1),
        which: "is the joint",
        flag: "--joint NAME",
    };
    let mut r = read_joints(&bytes, &file, topic, stamps, wanted)?;
    let first = |v: &mut Vec<Vec<f64>>| v.pop().unwrap_or_default();
    Ok(JointSamples {
        label: format!("{file}#{}", r.topic),
        joint: r.joints.pop().unwrap_or_default(),
        t: r.t,
        position: first(&mut r.position),
        velocity: r.velocity.as_mut().map(first),
        effort: first(&mut r.effort),
        notes: r.notes,
    })
}

/// One message of a bag, with its channel's topic, schema and encoding.
struct BagMessage {
    topic: String,
    schema: String,
    encoding: String,
    log_time: u64,
    data: Vec<u8>,
}

/// Every message of `bytes`, read with MCAP's sans-I/O reader with a record
/// length limit (the file's size) and chunk CRCs checked: the crate's own
/// message stream sets no limit inside chunks, and the garbage of a damaged
/// compressed chunk can hold a record length of 10¹⁸ bytes, which it would
/// try to allocate (an abort, not an error).
fn messages(bytes: &[u8]) -> mcap::McapResult<Vec<BagMessage>> {
    use mcap::records::Record;
    use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
    use std::collections::HashMap;
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_record_length_limit(bytes.len())
            .with_validate_chunk_crcs(true),
    );
    let mut rest = bytes;
    let mut schemas: HashMap<u16, String> = HashMap::new();
    let mut channels: HashMap<u16, (String, u16, String)> = HashMap::new();
    let mut out = Vec::new();
    while let Some(event) = reader.next_event() {
        match event? {
            LinearReadEvent::ReadRequest(need) => {
                let n = need.min(rest.len());
                reader.insert(n).copy_from_slice(&rest[..n]);
                reader.notify_read(n);
                rest = &rest[n..];
            }
            LinearReadEvent::Record { data, opcode } => match mcap::parse_record(opcode, data)? {
                Record::Schema { header, .. } => {
                    schemas.insert(header.id, header.name);
                }
                Record::Channel(c) => {
                    channels.insert(c.id, (c.topic, c.schema_id, c.message_encoding));
                }
                Record::Message { header, data } => {
                    let Some((topic, schema_id, encoding)) = channels.get(&header.channel_id)
                    else {
                        return Err(mcap::McapError::UnknownChannel(
                            header.sequence,
                            header.channel_id,
                        ));
                    };
                    out.push(BagMessage {
                        topic: topic.clone(),
                        schema: schemas
                            .get(schema_id)
                            .cloned()
                            .unwrap_or_else(|| "(no schema)".into()),
                        encoding: encoding.clone(),
                        log_time: header.log_time,
                        data: data.into_owned(),
                    });
                }
                _ => {}
            },
        }
    }
    Ok(out)
}

/// Largest ratio of a chunk's declared uncompressed size to its compressed
/// records: far beyond what zstd or lz4 give on joint states (single
/// digits), and what keeps a damaged size field from being allocated.
const MAX_CHUNK_RATIO: u64 = 1024;

/// Checks every chunk's declared uncompressed size before the MCAP reader
/// allocates it: a damaged size field (e.g. 1.7e18 bytes) would abort the
/// process instead of giving an error. The record walk ends at the first
/// record the file cuts short (after checking it, if it is a chunk); the
/// reader then reports the damage itself.
fn check_chunk_sizes(bytes: &[u8]) -> Result<(), String> {
    const CHUNK: u8 = 0x06;
    let u64_at = |b: &[u8], at: usize| -> Option<u64> {
        b.get(at..at + 8)
            .map(|s| u64::from_le_bytes(s.try_into().expect("8 bytes")))
    };
    let u32_at = |b: &[u8], at: usize| -> Option<u32> {
        b.get(at..at + 4)
            .map(|s| u32::from_le_bytes(s.try_into().expect("4 bytes")))
    };
    let mut at = MCAP_MAGIC.len();
    while let (Some(&op), Some(len)) = (bytes.get(at), u64_at(bytes, at + 1)) {
        let start = at + 9;
        // A record cut short by the end of the file is still read from its
        // header on (a chunk's sizes come first): its sizes are checked on
        // what is there, and the walk ends with it.
        let whole = usize::try_from(len)
            .ok()
            .and_then(|l| bytes.get(start..start.checked_add(l)?));
        let cut = whole.is_none();
        let body = whole.unwrap_or_else(|| bytes.get(start..).unwrap_or_default());
        if op == CHUNK {
            // start time, end time, uncompressed size, crc, compression, records.
            let damaged = |what: String| {
                Err(format!(
                    "the chunk at byte {at} {what}: the file is damaged (re-record or re-copy \
                     the bag)"
                ))
            };
            let (Some(declared), Some(name_len)) = (u64_at(body, 16), u32_at(body, 28)) else {
                return damaged("is cut short".into());
            };
            let records_at = 32 + name_len as usize;
            let Some(records) = u64_at(body, records_at) else {
                return damaged("is cut short".into());
            };
            let room = (body.len() - (records_at + 8).min(body.len())) as u64;
            if records > room {
                return damaged(format!(
                    "declares {records} bytes of records but holds {room}"
                ));
            }
            if declared
                > records
                    .saturating_mul(MAX_CHUNK_RATIO)
                    .saturating_add(1 << 20)
            {
                return damaged(format!(
                    "declares {declared} uncompressed bytes for {records} compressed ones"
                ));
            }
        }
        if cut {
            return Ok(());
        }
        at = start + body.len();
    }
    Ok(())
}

#[cfg(feature = "bags")]
/// Reads the `wanted` joints of a `JointState` topic of the MCAP file
/// `bytes`; `file` names it in messages.
pub(crate) fn read_joints(
    bytes: &[u8],
    file: &str,
    topic: Option<&str>,
    stamps: Stamps,
    wanted: Wanted<'_>,
) -> Result<JointRows, LogError> {
    let bag_err = |reason: String| LogError::Bag {
        file: file.into(),
        reason,
    };
    check_chunk_sizes(bytes).map_err(bag_err)?;
    let all = messages(bytes).map_err(|e| bag_err(e.to_string()))?;
    let topics = topic_infos(&all);
    let topic = choose_topic(&topics, topic, file)?;
    let mut rows = TopicRows::new(file, topic.clone(), stamps, &wanted);
    for msg in all.iter().filter(|m| m.topic == topic) {
        rows.message(msg)?;
    }
    Ok(rows.finish(&topics))
}

/// Pass 1: the bag's topics and their message counts.
#[cfg(feature = "bags")]
fn topic_infos(all: &[BagMessage]) -> BTreeMap<String, TopicInfo> {
    let mut topics: BTreeMap<String, TopicInfo> = BTreeMap::new();
    for m in all {
        let info = topics.entry(m.topic.clone()).or_insert_with(|| TopicInfo {
            schema: m.schema.clone(),
            encoding: m.encoding.clone(),
            messages: 0,
        });
        info.messages += 1;
    }
    topics
}

/// The `JointState` topic to read: the one asked for, else the bag's only
/// one; it must be CDR-encoded.
#[cfg(feature = "bags")]
fn choose_topic(
    topics: &BTreeMap<String, TopicInfo>,
    topic: Option<&str>,
    file: &str,
) -> Result<String, LogError> {
    let topic_err = |problem: String| LogError::BagTopic {
        file: file.into(),
        problem,
        topics: topic_list(topics, false),
    };
    let topic = match topic {
        Some(t) => match topics.get(t) {
            None => return Err(topic_err(format!("the bag has no topic `{t}`"))),
            Some(i) if i.schema != JOINT_STATE => {
                return Err(topic_err(format!(
                    "topic `{t}` holds {}, not {JOINT_STATE}",
                    i.schema
                )));
            }
            Some(_) => t.to_string(),
        },
        None => {
            let js: Vec<&String> = topics
                .iter()
                .filter(|(_, i)| i.schema == JOINT_STATE)
                .map(|(t, _)| t)
                .collect();
            match js.as_slice() {
                [] => return Err(topic_err(format!("the bag has no {JOINT_STATE} topic"))),
                [one] => (*one).clone(),
                _ => {
                    return Err(LogError::BagTopic {
                        file: file.into(),
                        problem: format!(
                            "the bag has {} {JOINT_STATE} topics: choose one with --topic \
                             (BagOptions::topic)",
                            js.len()
                        ),
                        topics: topic_list(topics, true),
                    });
                }
            }
        }
    };
    let info = &topics[&topic];
    if info.encoding != "cdr" {
        return Err(topic_err(format!(
            "topic `{topic}` is encoded as `{}`; ROS 2 bags encode messages as `cdr`",
            info.encoding
        )));
    }
    Ok(topic)
}

/// Pass 2: the chosen joints' rows decoded from the topic's messages, one
/// message at a time, with what the notes report about them.
#[cfg(feature = "bags")]
struct TopicRows<'w> {
    file: String,
    topic: String,
    stamps: Stamps,
    wanted: &'w Wanted<'w>,
    /// Joints expected before the first message fixes them.
    count: Option<usize>,
    /// The joints read, by name (`None` until the first message when not
    /// given).
    joints: Option<Vec<String>>,
    t: Vec<f64>,
    position: Vec<Vec<f64>>,
    velocity: Vec<Vec<f64>>,
    effort: Vec<Vec<f64>>,
    /// True while every message has every joint's velocity.
    has_velocity: bool,
    notes: Vec<String>,
    /// The first message's time and the previous one's (ns).
    first_ns: Option<i64>,
    prev_ns: i64,
    /// Steps between messages (ns), for the rate note.
    steps: Vec<i64>,
    /// Range of the log time's lag behind `header.stamp` (ns).
    latency: Option<[i64; 2]>,
    /// Joints in the messages that are not read.
    extra: Vec<String>,
    /// The current message's number on the topic (1-based).
    number: u64,
}

#[cfg(feature = "bags")]
impl<'w> TopicRows<'w> {
    fn new(file: &str, topic: String, stamps: Stamps, wanted: &'w Wanted<'w>) -> Self {
        let count = wanted
            .names
            .as_ref()
            .map_or(wanted.count, |n| Some(n.len()));
        let columns = vec![Vec::new(); count.unwrap_or(0)];
        Self {
            file: file.into(),
            topic,
            stamps,
            wanted,
            count,
            joints: wanted.names.clone(),
            t: Vec::new(),
            position: columns.clone(),
            velocity: columns.clone(),
            effort: columns,
            has_velocity: true,
            notes: Vec::new(),
            first_ns: None,
            prev_ns: 0,
            steps: Vec::new(),
            latency: None,
            extra: Vec::new(),
            number: 0,
        }
    }

    /// An error about the current message.
    fn at(&self, problem: String) -> LogError {
        LogError::BagMessage {
            file: self.file.clone(),
            topic: self.topic.clone(),
            message: self.number,
            problem,
        }
    }

    /// Decodes one message of the topic into a row.
    fn message(&mut self, msg: &BagMessage) -> Result<(), LogError> {
        self.number += 1;
        let mut state = JointState::default();
        decode(&msg.data, &mut state).map_err(|p| self.at(p))?;
        let stamp_ns = i64::from(state.sec) * 1_000_000_000 + i64::from(state.nanosec);
        let log_ns = i64::try_from(msg.log_time).unwrap_or(i64::MAX);
        let ns = match self.stamps {
            Stamps::Header => stamp_ns,
            Stamps::Log => log_ns,
        };
        if self.joints.is_none() {
            self.first_joints(&state.names)?;
        }
        let Some(index) = self.indices(&state.names)? else {
            return Ok(());
        };
        self.check_lengths(&state)?;
        let t = self.time(ns, stamp_ns)?;
        self.prev_ns = ns;
        if self.stamps == Stamps::Header {
            let d = log_ns.saturating_sub(stamp_ns);
            self.latency = Some(
                self.latency
                    .map_or([d, d], |[lo, hi]| [lo.min(d), hi.max(d)]),
            );
        }
        self.t.push(t);
        for (k, &i) in index.iter().enumerate() {
            let p = self.value(&state.position, i, k, "position")?;
            self.position[k].push(p);
            let e = self.value(&state.effort, i, k, "effort")?;
            self.effort[k].push(e);
            if self.has_velocity {
                let v = self.value(&state.velocity, i, k, "velocity")?;
                self.velocity[k].push(v);
            }
        }
        Ok(())
    }

    /// No joints named: the first message's, if it names as many as
    /// wanted, in its order (with a note).
    fn first_joints(&mut self, names: &[&str]) -> Result<(), LogError> {
        let wanted = self.wanted;
        if self.count.is_some_and(|c| names.len() != c) || names.is_empty() {
            return Err(LogError::BagJoints {
                file: self.file.clone(),
                topic: self.topic.clone(),
                problem: format!(
                    "the first message names {} joints ({}): say which {} with {}",
                    names.len(),
                    names.join(", "),
                    wanted.which,
                    wanted.flag
                ),
            });
        }
        let c = names.len();
        self.count = Some(c);
        for out in [&mut self.position, &mut self.velocity, &mut self.effort] {
            out.resize(c, Vec::new());
        }
        let roles: Vec<String> = names
            .iter()
            .enumerate()
            .map(|(k, n)| format!("{} = joint `{n}`", (wanted.role)(k)))
            .collect();
        self.notes.push(format!(
            "{}: {} (choose with {})",
            roles.join(", "),
            match c {
                1 => "the only joint of the first message".to_string(),
                2 => "the two joints in the order of the first message".to_string(),
                n => format!("the {n} joints in the order of the first message"),
            },
            wanted.flag
        ));
        self.joints = Some(names.iter().map(|n| n.to_string()).collect());
        Ok(())
    }

    /// Where each chosen joint is in this message's arrays; the joints it
    /// names beyond them are noted.
    fn indices(&mut self, names: &[&str]) -> Result<Option<Vec<usize>>, LogError> {
        let Some(chosen) = self.joints.as_ref() else {
            return Ok(None);
        };
        let mut index = vec![0usize; chosen.len()];
        for (k, j) in chosen.iter().enumerate() {
            index[k] = names.iter().position(|n| *n == j.as_str()).ok_or_else(|| {
                self.at(format!(
                    "joint `{j}` ({}) is not in the message, which names: {}; check {}",
                    (self.wanted.role)(k),
                    if names.is_empty() {
                        "no joints".to_string()
                    } else {
                        names.join(", ")
                    },
                    self.wanted.flag
                ))
            })?;
        }
        for n in names {
            if !chosen.iter().any(|c| c == n) && !self.extra.iter().any(|e| e == n) {
                self.extra.push(n.to_string());
            }
        }
        Ok(Some(index))
    }

    /// Every joint needs its position and effort; a message without every
    /// velocity turns the velocities off for the log.
    fn check_lengths(&mut self, state: &JointState<'_>) -> Result<(), LogError> {
        let n = state.names.len();
        if state.position.len() != n {
            return Err(self.at(format!(
                "it names {n} joints but has {} positions: each joint needs its position",
                state.position.len()
            )));
        }
        if state.effort.is_empty() {
            return Err(self.at(format!(
                "it has no effort: aras needs the joint torques (N·m); record effort in the \
                 {JOINT_STATE} messages (the joint driver's measured torque), or give a CSV log \
                 with tau1, tau2"
            )));
        }
        if state.effort.len() != n {
            return Err(self.at(format!(
                "it names {n} joints but has {} efforts: each joint needs its effort",
                state.effort.len()
            )));
        }
        if self.has_velocity && state.velocity.len() != n {
            self.has_velocity = false;
            if self.number > 1 {
                self.notes.push(format!(
                    "message {} has no velocity for every joint: joint rates are computed \
                     from the angles",
                    self.number
                ));
            }
        }
        Ok(())
    }

    /// The message's time (s) from the first message's; it must increase.
    fn time(&mut self, ns: i64, stamp_ns: i64) -> Result<f64, LogError> {
        let Some(ns0) = self.first_ns else {
            self.first_ns = Some(ns);
            return Ok(0.0);
        };
        if ns <= self.prev_ns {
            let hint = match self.stamps {
                Stamps::Header if stamp_ns == 0 => {
                    "header.stamp is zero: the driver does not fill it; read the bag's \
                     log time instead with --stamps log (BagOptions::stamps)"
                }
                Stamps::Header => {
                    "the driver's stamps go backwards or repeat; if they are unreliable, \
                     read the bag's log time with --stamps log"
                }
                Stamps::Log => "the bag's log time goes backwards or repeats",
            };
            return Err(self.at(format!(
                "its time {} s does not follow the previous message's {} s: {hint}",
                (ns - ns0) as f64 / 1e9,
                (self.prev_ns - ns0) as f64 / 1e9
            )));
        }
        self.steps.push(ns - self.prev_ns);
        Ok((ns - ns0) as f64 / 1e9)
    }

    /// Joint `k`'s value at index `i` of `v`, which must be finite.
    fn value(&self, v: &[f64], i: usize, k: usize, field: &str) -> Result<f64, LogError> {
        let x = v[i];
        if x.is_finite() {
            return Ok(x);
        }
        let joint = self.joints.as_ref().map_or("", |j| j[k].as_str());
        Err(self.at(format!(
            "{field} of joint `{joint}` is {x}: logs must hold finite numbers only (drop the \
             message or repair the recording)"
        )))
    }

    /// The rows, with the notes: the topic and time origin first, then the
    /// message rate, the log time's lag, the joints and topics ignored.
    fn finish(mut self, topics: &BTreeMap<String, TopicInfo>) -> JointRows {
        let origin = self.first_ns.map_or(0.0, |n| n as f64 / 1e9);
        let time = match self.stamps {
            Stamps::Header => format!("t = 0 at the first message's header.stamp ({origin} s)"),
            Stamps::Log => {
                format!("t = 0 at the first message's log time ({origin} s; --stamps log)")
            }
        };
        self.notes.insert(
            0,
            format!(
                "ROS 2 bag: topic {}, {} {JOINT_STATE} messages; {time}{}",
                self.topic,
                self.number,
                if self.has_velocity {
                    "; joint rates from velocity"
                } else {
                    ""
                }
            ),
        );
        if !self.steps.is_empty() {
            let mut sorted = self.steps.clone();
            sorted.sort_unstable();
            let median = sorted[sorted.len() / 2];
            let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
            self.notes.push(format!(
                "message rate {} Hz (median step {} ms; steps {}–{} ms, i.e. {}–{} Hz)",
                crate::error::sig(1e9 / median as f64),
                ms(median),
                ms(lo),
                ms(hi),
                crate::error::sig(1e9 / hi as f64),
                crate::error::sig(1e9 / lo as f64),
            ));
        }
        if let Some([lo, hi]) = self.latency {
            self.notes.push(format!(
                "the bag's log time trails header.stamp by {}–{} ms",
                ms(lo),
                ms(hi)
            ));
        }
        if !self.extra.is_empty() {
            self.notes
                .push(format!("joints ignored: {}", self.extra.join(", ")));
        }
        let others: Vec<&str> = topics
            .keys()
            .map(String::as_str)
            .filter(|t| *t != self.topic)
            .collect();
        if !others.is_empty() {
            self.notes
                .push(format!("other topics ignored: {}", others.join(", ")));
        }
        JointRows {
            t: self.t,
            position: self.position,
            velocity: self.has_velocity.then_some(self.velocity),
            effort: self.effort,
            topic: self.topic,
            joints: self.joints.unwrap_or_default(),
            notes: self.notes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A little-endian CDR JointState, built by hand.
    fn message(names: &[&str], pos: &[f64], vel: &[f64], eff: &[f64]) -> Vec<u8> {
        let mut b = vec![0u8, 1, 0, 0];
        let pad = |b: &mut Vec<u8>, n: usize| {
            while !(b.len() - 4).is_multiple_of(n) {
                b.push(0);
            }
        };
        let u32 = |b: &mut Vec<u8>, x: u32| {
            pad(b, 4);
            b.extend(x.to_le_bytes());
        };
        let string = |b: &mut Vec<u8>, s: &str| {
            u32(b, s.len() as u32 + 1);
            b.extend(s.as_bytes());
            b.push(0);
        };
        u32(&mut b, 12);
        u32(&mut b, 500);
        string(&mut b, "base");
        u32(&mut b, names.len() as u32);
        for n in names {
            string(&mut b, n);
        }
        for seq in [pos, vel, eff] {
            u32(&mut b, seq.len() as u32);
            for x in seq {
                pad(&mut b, 8);
                b.extend(x.to_le_bytes());
            }
        }
        b
    }

    #[test]
    fn cdr_joint_state_decodes_and_truncation_is_an_error() {
        let data = message(&["a", "bb"], &[1.5, -2.0], &[], &[0.25, 3.0]);
        let mut m = JointState::default();
        decode(&data, &mut m).unwrap();
        assert_eq!((m.sec, m.nanosec), (12, 500));
        assert_eq!(m.names, ["a", "bb"]);
        assert_eq!(m.position, [1.5, -2.0]);
        assert!(m.velocity.is_empty());
        assert_eq!(m.effort, [0.25, 3.0]);
        for cut in [2, 10, data.len() - 1] {
            let mut m = JointState::default();
            let e = decode(&data[..cut], &mut m).unwrap_err();
            assert!(
                e.contains("truncated") || e.contains("4-byte"),
                "{cut}: {e}"
            );
        }
        let mut pl = data.clone();
        pl[1] = 3;
        let mut m = JointState::default();
        assert!(decode(&pl, &mut m).unwrap_err().contains("not plain CDR"));
    }

    proptest::proptest! {
        /// Any bytes decode or fail with a message: no panic, no huge
        /// allocation from a corrupt length.
        #[test]
        fn cdr_decoder_never_panics(
            mut bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..200),
            header in 0u8..3,
        ) {
            if bytes.len() >= 2 {
                bytes[0] = 0;
                bytes[1] = header;
            }
            let mut m = JointState::default();
            let _ = decode(&bytes, &mut m);
        }
    }

    #[test]
    fn joint_names_parse() {
        let j = JointNames::parse("theta1=motor_left, theta2=Motor_Right").unwrap();
        assert_eq!(j.names, ["motor_left", "Motor_Right"]);
        let j = JointNames::parse("theta3=c,theta1=a,theta2=b").unwrap();
        assert_eq!(j.names, ["a", "b", "c"]);
        assert_eq!(JointNames::parse("theta1=a").unwrap().names, ["a"]);
        for bad in ["q1=a", "theta1=a,theta2=a", "theta3=a,theta2=b", "theta1"] {
            assert!(JointNames::parse(bad).is_err(), "{bad}");
        }
    }
}
