//! The DDS side (ros2-client on RustDDS, no ROS install): the bridge node and the fake arm.
//!
//! QoS: the JointState subscription is best-effort (it matches a best-effort or a reliable
//! publisher, as `ros2 topic echo --qos-reliability best_effort` does), keep-last 1000; the
//! outputs are published reliably, keep-last 100, volatile.

use std::collections::BTreeMap;
use std::net::Ipv4Addr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use admittance_bag::msgs::{Float64MultiArray, Header, JointState, Time, WrenchStamped};
use ros2_client::qos::{History, WhenFull};
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile,
    Subscription,
};
use rustdds_api::mio1::{Events, Interest, Poll, Token};
use rustdds_api::DomainParticipantBuilder;
use serde::{Deserialize, Serialize};

use crate::bridge::{contact_message, status_message, Bridge};
use crate::stats::{stamp_rate, BridgeStats, Percentiles};

use ros2_client::dds::rustdds as rustdds_api;

/// Where the node is: the DDS domain and whether it stays on this machine.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DdsOptions {
    /// `ROS_DOMAIN_ID`.
    pub domain_id: u16,
    /// Discovery and traffic on the loopback interface only (`ROS_LOCALHOST_ONLY=1`).
    pub localhost_only: bool,
}

impl DdsOptions {
    /// From `ROS_DOMAIN_ID` and `ROS_LOCALHOST_ONLY`, unless given; an unreadable
    /// `ROS_DOMAIN_ID` is an error naming it.
    pub fn from_env(domain_id: Option<u16>, localhost_only: bool) -> Result<Self, String> {
        let domain_id = match domain_id {
            Some(d) => d,
            None => match std::env::var("ROS_DOMAIN_ID") {
                Ok(v) if !v.trim().is_empty() => v
                    .trim()
                    .parse::<u16>()
                    .ok()
                    .filter(|d| *d <= 232)
                    .ok_or_else(|| format!("ROS_DOMAIN_ID `{v}` is not a domain id (0 to 232)"))?,
                _ => 0,
            },
        };
        let env_local = std::env::var("ROS_LOCALHOST_ONLY").is_ok_and(|v| v.trim() == "1");
        Ok(Self {
            domain_id,
            localhost_only: localhost_only || env_local,
        })
    }

    /// A ROS 2 context on this domain: with `localhost_only`, RustDDS uses the loopback
    /// interface alone for multicast and advertised locators, and finds the other
    /// participants of this machine through its localhost unicast discovery peers.
    pub fn context(&self) -> Result<Context, String> {
        let mut builder = DomainParticipantBuilder::new(self.domain_id);
        if self.localhost_only {
            builder = builder.with_only_networks([Ipv4Addr::LOCALHOST]);
        }
        let participant = builder
            .build()
            .map_err(|e| format!("DDS participant on domain {}: {e}", self.domain_id))?;
        Context::from_domain_participant(participant)
            .map_err(|e| format!("ROS 2 context on domain {}: {e}", self.domain_id))
    }
}

/// A topic name as ros2-client takes it, or an error naming it.
pub fn topic_name(topic: &str) -> Result<Name, String> {
    Name::parse(topic).map_err(|e| format!("topic `{topic}` is not a ROS 2 name: {e:?}"))
}

fn node(context: &Context, name: &str) -> Result<Node, String> {
    let (ns, base) = match name.rsplit_once('/') {
        Some((ns, base)) => (if ns.is_empty() { "/" } else { ns }, base),
        None => ("/", name),
    };
    let node_name = NodeName::new(ns, base).map_err(|e| format!("node name `{name}`: {e:?}"))?;
    context
        .new_node(node_name, NodeOptions::new().enable_rosout(false))
        .map_err(|e| format!("node `{name}`: {e:?}"))
}

const JOINT_STATE_TYPE: (&str, &str) = ("sensor_msgs", "JointState");
const WRENCH_STAMPED_TYPE: (&str, &str) = ("geometry_msgs", "WrenchStamped");
const FLOAT64_MULTI_ARRAY_TYPE: (&str, &str) = ("std_msgs", "Float64MultiArray");

/// Best-effort, keep-last 1000: the sensor-data input. The deep queue keeps every message
/// through a stall of the bridge's thread of up to a second at 1 kHz (the observer wants
/// every sample, late rather than never).
fn input_qos() -> QosProfile {
    QosProfile::subscription_default().history(History::KeepLast { depth: 1000 })
}

/// Reliable, keep-last `depth`: the outputs.
fn output_qos(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Wait(Duration::from_millis(10)))
        .history(History::KeepLast { depth })
}

fn subscribe<M: 'static + serde::de::DeserializeOwned>(
    node: &mut Node,
    topic: &str,
    type_name: (&str, &str),
    qos: QosProfile,
) -> Result<Subscription<M>, String> {
    let t = node
        .create_topic(
            &topic_name(topic)?,
            MessageTypeName::new(type_name.0, type_name.1),
            &qos,
        )
        .map_err(|e| format!("topic `{topic}`: {e:?}"))?;
    node.create_subscription::<M>(&t, Some(qos))
        .map_err(|e| format!("subscription to `{topic}`: {e:?}"))
}

fn publisher<M: Serialize>(
    node: &mut Node,
    topic: &str,
    type_name: (&str, &str),
    qos: QosProfile,
) -> Result<Publisher<M>, String> {
    let t = node
        .create_topic(
            &topic_name(topic)?,
            MessageTypeName::new(type_name.0, type_name.1),
            &qos,
        )
        .map_err(|e| format!("topic `{topic}`: {e:?}"))?;
    node.create_publisher::<M>(&t, Some(qos))
        .map_err(|e| format!("publisher on `{topic}`: {e:?}"))
}

/// Wall-clock nanoseconds since the epoch.
pub fn wall_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i64)
}

/// The bridge node's topics and limits.
#[derive(Clone, Debug)]
pub struct BridgeTopics {
    /// The node's name (`/admittance_bridge`).
    pub node_name: String,
    /// External joint torques (JointState, effort).
    pub torque_topic: String,
    /// Hand wrench (WrenchStamped).
    pub wrench_topic: String,
    /// The admittance model's compliant reference (JointState position, velocity), if wanted.
    pub reference_topic: Option<String>,
    /// Contact flags and the touched link's wrench (Float64MultiArray
    /// `[contact, collision, link, fx, fy, fz, mx, my, mz]`), published when the
    /// loop has a contact floor.
    pub contact_topic: String,
    /// The loop's status flags (Float64MultiArray, `STATUS_LABEL`'s order), published after
    /// each torque message.
    pub status_topic: String,
    /// Stop after this long (none: until SIGINT or SIGTERM).
    pub duration: Option<Duration>,
}

/// Runs the bridge until `stop` is set or the duration is over: each message of the
/// input topic is stepped and answered. Per-message problems are counted, never fatal.
pub fn run_bridge(
    bridge: &mut Bridge,
    dds: &DdsOptions,
    topics: &BridgeTopics,
    stop: &AtomicBool,
    mut on_skip: impl FnMut(&str, &str),
) -> Result<BridgeStats, String> {
    let context = dds.context()?;
    let mut node = node(&context, &topics.node_name)?;
    let input = bridge.input_map().topic.clone();
    let mut subscription =
        subscribe::<JointState>(&mut node, &input, JOINT_STATE_TYPE, input_qos())?;
    let torque_pub = publisher::<JointState>(
        &mut node,
        &topics.torque_topic,
        JOINT_STATE_TYPE,
        output_qos(100),
    )?;
    let wrench_pub = publisher::<WrenchStamped>(
        &mut node,
        &topics.wrench_topic,
        WRENCH_STAMPED_TYPE,
        output_qos(100),
    )?;
    let contact_pub = publisher::<Float64MultiArray>(
        &mut node,
        &topics.contact_topic,
        FLOAT64_MULTI_ARRAY_TYPE,
        output_qos(100),
    )?;
    let status_pub = publisher::<Float64MultiArray>(
        &mut node,
        &topics.status_topic,
        FLOAT64_MULTI_ARRAY_TYPE,
        output_qos(100),
    )?;
    let reference_pub = match &topics.reference_topic {
        Some(t) => Some(publisher::<JointState>(
            &mut node,
            t,
            JOINT_STATE_TYPE,
            output_qos(100),
        )?),
        None => None,
    };
    let mut poll = Poll::new().map_err(|e| format!("poll: {e}"))?;
    poll.registry()
        .register(&mut subscription, Token(0), Interest::READABLE)
        .map_err(|e| format!("poll registration of `{input}`: {e}"))?;
    let mut events = Events::with_capacity(16);
    let mut stats = BridgeStats {
        topic: input.clone(),
        loop_rate_hz: 1.0 / bridge.dt(),
        ..Default::default()
    };
    let mut receipt_ns: Vec<i64> = Vec::with_capacity(1 << 16);
    let mut take_ns: Vec<i64> = Vec::with_capacity(1 << 16);
    let mut stamps: Vec<i64> = Vec::with_capacity(1 << 16);
    let start = Instant::now();
    loop {
        if stop.load(Ordering::Relaxed) || topics.duration.is_some_and(|d| start.elapsed() >= d) {
            break;
        }
        // Edge-triggered: after a wake-up read until the reader is empty; the timeout only
        // bounds how late a stop is noticed.
        if let Err(e) = poll.poll(&mut events, Some(Duration::from_millis(50))) {
            if e.kind() != std::io::ErrorKind::Interrupted {
                return Err(format!("poll: {e}"));
            }
        }
        loop {
            let taken = Instant::now();
            let (msg, info) = match subscription.take() {
                Ok(Some(m)) => m,
                Ok(None) => break,
                Err(e) => {
                    stats.received += 1;
                    let detail = format!("{input}: not a sensor_msgs/msg/JointState: {e}");
                    stats.skip("undecodable", &detail);
                    on_skip("undecodable", &detail);
                    continue;
                }
            };
            stats.received += 1;
            match bridge.process(&msg) {
                Ok(stepped) => {
                    let header = Header {
                        stamp: msg.header.stamp,
                        frame_id: msg.header.frame_id.clone(),
                    };
                    let mut ok = torque_pub.publish(bridge.torque_message(&header)).is_ok();
                    ok &= wrench_pub.publish(bridge.wrench_message(&header)).is_ok();
                    if let Some(p) = &reference_pub {
                        ok &= p.publish(bridge.reference_message(&header)).is_ok();
                    }
                    let wrench = bridge.rust_loop().contact_wrench().map(|(base, _)| base);
                    if let Some(flags) = contact_message(&stepped.status, wrench) {
                        ok &= contact_pub.publish(flags).is_ok();
                    }
                    ok &= status_pub.publish(status_message(&stepped.status)).is_ok();
                    let done_wall = wall_ns();
                    take_ns.push(taken.elapsed().as_nanos() as i64);
                    if let Some(r) = info.received_timestamp() {
                        receipt_ns.push(done_wall - r.to_nanos());
                    }
                    stamps.push(stepped.stamp_ns);
                    if ok {
                        stats.stepped += 1;
                    } else {
                        stats.publish_errors += 1;
                    }
                }
                Err(e) => {
                    stats.skip(e.reason, &e.detail);
                    on_skip(e.reason, &e.detail);
                }
            }
        }
    }
    stats.receipt_to_publish = Percentiles::of(&mut receipt_ns);
    stats.take_to_publish = Percentiles::of(&mut take_ns);
    stats.stamp_rate_hz = stamp_rate(&stamps);
    Ok(stats)
}

/// The fake arm's settings.
#[derive(Clone, Debug)]
pub struct FakeArmOptions {
    /// The JointState topic it publishes (best-effort).
    pub topic: String,
    /// Joint names, in the order of the published arrays.
    pub joints: Vec<String>,
    /// Publishing rate (Hz).
    pub rate_hz: f64,
    /// How long it publishes after discovery.
    pub duration: Duration,
    /// The bridge's torque topic it listens to.
    pub torque_topic: String,
    /// How long it waits for the bridge's first answer.
    pub discovery_timeout: Duration,
}

/// One answer of the bridge as the fake arm received it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Answer {
    /// The answered message's stamp (ns).
    pub stamp_ns: i64,
    /// The joint names of the answer.
    pub name: Vec<String>,
    /// The estimate (effort).
    pub effort: Vec<f64>,
}

/// What the fake arm saw.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FakeArmReport {
    /// The input topic.
    pub topic: String,
    /// The joint names as published.
    pub joints: Vec<String>,
    /// The first message's stamp (ns); message `k` is stamped `t0_ns + k * period_ns`.
    pub t0_ns: i64,
    /// The period (ns).
    pub period_ns: i64,
    /// Messages published before the bridge's first answer arrived (discovery).
    pub discovery_messages: u64,
    /// Seconds from the first message to the first answer.
    pub discovery_s: f64,
    /// Messages published in the measured window (after discovery).
    pub window_messages: u64,
    /// Of those, how many were answered.
    pub window_answered: u64,
    /// `window_answered / window_messages`.
    pub delivered_share: f64,
    /// The achieved publishing rate over the window (Hz).
    pub publish_rate_hz: f64,
    /// From publishing a message to receiving its answer.
    pub round_trip: Percentiles,
    /// Every answer received (discovery included), in order of arrival.
    pub answers: Vec<Answer>,
}

/// The fake arm's mean pose (rad), by joint rank: within the limits of a Panda or FR3.
const FAKE_POSE: [f64; 7] = [-0.4, -0.2, 0.0, -2.0, 0.4, 1.5, 0.8];

/// Message `k` of the fake arm: smooth motion of every joint (exact velocities) and
/// torques, stamped `t0_ns + k * period_ns`; names in `joints`' order, each joint's values
/// a function of its name's rank in sorted order. The angles swing by 0.3 rad around a
/// pose inside a Franka arm's joint limits (the bridge's plausibility gates refuse angles
/// beyond them).
pub fn fake_sample(k: u64, joints: &[String], t0_ns: i64, period_ns: i64) -> JointState {
    let stamp = t0_ns + k as i64 * period_ns;
    let t = k as f64 * period_ns as f64 * 1e-9;
    let mut m = JointState {
        header: Header {
            stamp: Time {
                sec: (stamp.div_euclid(1_000_000_000)) as i32,
                nanosec: stamp.rem_euclid(1_000_000_000) as u32,
            },
            frame_id: String::new(),
        },
        name: joints.to_vec(),
        ..Default::default()
    };
    // Each joint's motion depends on its name's rank among the names, not on its place in
    // the message: the same arm whatever order the names are published in.
    let mut sorted: Vec<&String> = joints.iter().collect();
    sorted.sort();
    for name in joints {
        let f = sorted.iter().position(|s| *s == name).unwrap_or(0) as f64;
        let w = std::f64::consts::TAU / (3.0 + f);
        m.position
            .push(FAKE_POSE[f as usize % FAKE_POSE.len()] + 0.3 * (w * t).sin());
        m.velocity.push(0.3 * w * (w * t).cos());
        m.effort
            .push(1.5 * (1.0 + f) * (0.7 * t + f).sin() + 0.2 * f);
    }
    m
}

/// Publishes [`fake_sample`]s at `rate_hz` (best-effort) until the bridge's first answer
/// arrives on the torque topic, then for `duration` more, and collects the answers.
pub fn run_fake_arm(
    dds: &DdsOptions,
    opts: &FakeArmOptions,
    stop: &AtomicBool,
) -> Result<FakeArmReport, String> {
    if !(opts.rate_hz.is_finite() && opts.rate_hz > 0.0 && opts.rate_hz <= 100_000.0) {
        return Err(format!("--rate-hz {} is not in (0, 100000]", opts.rate_hz));
    }
    if opts.joints.is_empty() {
        return Err("no joint names (--joints)".into());
    }
    let context = dds.context()?;
    let mut node = node(&context, "/admittance_fake_arm")?;
    let publisher = publisher::<JointState>(
        &mut node,
        &opts.topic,
        JOINT_STATE_TYPE,
        QosProfile::subscription_default().history(History::KeepLast { depth: 10 }),
    )?;
    let answers_sub = subscribe::<JointState>(
        &mut node,
        &opts.torque_topic,
        JOINT_STATE_TYPE,
        QosProfile::publisher_default().history(History::KeepLast { depth: 10_000 }),
    )?;
    let period_ns = (1e9 / opts.rate_hz).round() as i64;
    // Stamps on whole milliseconds of the wall clock, as a robot stamps its samples.
    let t0_ns = (wall_ns() / 1_000_000) * 1_000_000;
    let mut published_at: Vec<i64> = Vec::new();
    let mut answers: Vec<Answer> = Vec::new();
    let mut answered_at: BTreeMap<i64, i64> = BTreeMap::new();
    let collect = |answers: &mut Vec<Answer>, answered_at: &mut BTreeMap<i64, i64>| {
        while let Ok(Some((m, _))) = answers_sub.take() {
            let stamp = m.header.stamp.nanos();
            answered_at.insert(stamp, wall_ns());
            answers.push(Answer {
                stamp_ns: stamp,
                name: m.name,
                effort: m.effort,
            });
        }
    };
    let start = Instant::now();
    let mut k: u64 = 0;
    let mut window: Option<(u64, Instant)> = None;
    loop {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        // Absolute deadlines: a late wake-up publishes at once (catching up), never drifts.
        let deadline = start + Duration::from_nanos(period_ns as u64 * k);
        let now = Instant::now();
        if deadline > now {
            std::thread::sleep(deadline - now);
        }
        let msg = fake_sample(k, &opts.joints, t0_ns, period_ns);
        publisher
            .publish(msg)
            .map_err(|e| format!("publishing on `{}`: {e:?}", opts.topic))?;
        published_at.push(wall_ns());
        k += 1;
        collect(&mut answers, &mut answered_at);
        match window {
            None => {
                if !answers.is_empty() {
                    window = Some((k, Instant::now()));
                } else if start.elapsed() > opts.discovery_timeout {
                    return Err(format!(
                        "no answer on `{}` within {:.0} s of publishing on `{}` (domain {}): is `admittance ros2 bridge` running with the same topics and domain?",
                        opts.torque_topic,
                        opts.discovery_timeout.as_secs_f64(),
                        opts.topic,
                        dds.domain_id
                    ));
                }
            }
            Some((_, since)) => {
                if since.elapsed() >= opts.duration {
                    break;
                }
            }
        }
    }
    let (first_window_k, since) = window.unwrap_or((k, Instant::now()));
    let window_s = since.elapsed().as_secs_f64();
    // The last answers: reliable, so they come; wait until quiet.
    let mut quiet = Instant::now();
    let mut last = answers.len();
    while quiet.elapsed() < Duration::from_millis(500) {
        std::thread::sleep(Duration::from_millis(5));
        collect(&mut answers, &mut answered_at);
        if answers.len() != last {
            last = answers.len();
            quiet = Instant::now();
        }
    }
    let window_messages = k - first_window_k;
    let window_answered = answered_at
        .keys()
        .filter(|&&s| {
            let j = (s - t0_ns) / period_ns;
            j >= first_window_k as i64 && j < k as i64
        })
        .count() as u64;
    let mut rtt: Vec<i64> = answered_at
        .iter()
        .filter_map(|(&s, &at)| {
            let j = usize::try_from((s - t0_ns) / period_ns).ok()?;
            published_at.get(j).map(|p| at - p)
        })
        .collect();
    let first_answer = answers.first().map(|a| a.stamp_ns);
    Ok(FakeArmReport {
        topic: opts.topic.clone(),
        joints: opts.joints.clone(),
        t0_ns,
        period_ns,
        discovery_messages: first_window_k,
        discovery_s: first_answer.map_or(0.0, |_| first_window_k as f64 * period_ns as f64 * 1e-9),
        window_messages,
        window_answered,
        delivered_share: if window_messages > 0 {
            window_answered as f64 / window_messages as f64
        } else {
            0.0
        },
        publish_rate_hz: if window_s > 0.0 {
            window_messages as f64 / window_s
        } else {
            0.0
        },
        round_trip: Percentiles::of(&mut rtt),
        answers,
    })
}
