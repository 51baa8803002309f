//! `admittance ros2 bridge` and `admittance ros2 fake-arm`: the arguments (shared by the
//! `admittance` command, built with `--features ros2`, and this crate's `admittance-ros2`
//! binary) and what they run.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use admittance_bag::Profile;
use clap::{Args, Subcommand};

use crate::bridge::{Bridge, BridgeConfig, WrenchFrame};
use crate::node::{run_bridge, run_fake_arm, BridgeTopics, DdsOptions, FakeArmOptions};

/// ROS 2 without ROS: the observer on a robot's JointState topic.
#[derive(Args, Debug)]
pub struct Ros2Args {
    #[command(subcommand)]
    /// What to run.
    pub command: Ros2Command,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Ros2Command {
    /// Subscribe to the robot's JointState topic, step the deployed loop's observer on each
    /// message and publish the external joint torques (JointState effort) and the hand
    /// wrench (WrenchStamped).
    Bridge(BridgeArgs),
    /// A stand-in robot: publish smooth JointState messages at a fixed rate, listen to the
    /// bridge's answers and report delivery and round-trip time.
    FakeArm(FakeArmArgs),
}

/// Where on the network.
#[derive(Args, Debug, Clone)]
pub struct NetArgs {
    /// The ROS 2 distribution of the other nodes (default: $ROS_DISTRO, else the one this
    /// build speaks).
    #[arg(long, value_name = "DISTRO")]
    pub distro: Option<String>,
    /// DDS domain (default: $ROS_DOMAIN_ID, else 0).
    #[arg(long, value_name = "ID")]
    pub domain_id: Option<u16>,
    /// Stay on this machine's loopback interface (as ROS_LOCALHOST_ONLY=1, which is also
    /// read).
    #[arg(long)]
    pub localhost_only: bool,
}

/// `admittance ros2 bridge`.
#[derive(Args, Debug)]
pub struct BridgeArgs {
    /// The deployment folder (`admittance deploy SCENARIO --out DIR`): the arm, observer,
    /// admittance model and control rate; nothing is trained here.
    pub deployment: PathBuf,
    /// Override a key of the folder's loop.toml (`KEY=VALUE`); repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,
    /// Which topic and fields give q, qdot, tau: franka, ur, lbr, or a profile TOML file.
    #[arg(long, default_value = "franka")]
    pub profile: String,
    /// The robot's joint names in the arm's chain order, when they differ from the URDF's
    /// (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub joints: Option<Vec<String>>,
    /// The node's name.
    #[arg(long, default_value = "/admittance_bridge")]
    pub node_name: String,
    /// Topic of the estimated external joint torques (JointState, effort).
    #[arg(long, default_value = "/admittance/external_joint_torques")]
    pub torque_topic: String,
    /// Topic of the estimated hand wrench (WrenchStamped).
    #[arg(long, default_value = "/admittance/external_wrench")]
    pub wrench_topic: String,
    /// Axes of the wrench: the base link's or the tip link's (its frame_id).
    #[arg(long, value_enum, default_value = "base")]
    pub wrench_frame: WrenchFrame,
    /// Topic of the contact flags and the touched link's wrench (Float64MultiArray
    /// `[contact, collision, link, fx, fy, fz, mx, my, mz]`, issue 31),
    /// published when the deployment has a contact floor (`[contact] floor`).
    #[arg(long, default_value = "/admittance/contact")]
    pub contact_topic: String,
    /// Topic of the loop's status flags after each torque message (Float64MultiArray `[controller_fault,
    /// observer_fault, nonfinite_input, implausible_input, waiting_for_angles, warmup,
    /// holding_pose, stale_input, outside_training_range, faster_than_training]`, 1 or 0).
    #[arg(long, default_value = "/admittance/status")]
    pub status_topic: String,
    /// Also publish the admittance model's compliant reference (JointState position and
    /// velocity) on this topic.
    #[arg(long)]
    pub reference_topic: Option<String>,
    /// Stop after this many seconds (default: at Ctrl-C or SIGTERM).
    #[arg(long, value_name = "S")]
    pub duration: Option<f64>,
    /// Write the statistics (counts, skips, latency) as JSON to this file at exit.
    #[arg(long, value_name = "FILE")]
    pub stats: Option<PathBuf>,
    #[command(flatten)]
    /// Network.
    pub net: NetArgs,
}

/// `admittance ros2 fake-arm`.
#[derive(Args, Debug)]
pub struct FakeArmArgs {
    /// The profile whose JointState topic to publish on (franka, ur, lbr or a TOML file).
    #[arg(long, default_value = "franka")]
    pub profile: String,
    /// Joint names, in the order of the published arrays (comma-separated).
    #[arg(long, value_delimiter = ',', required = true)]
    pub joints: Vec<String>,
    /// Messages per second.
    #[arg(long, default_value_t = 1000.0)]
    pub rate_hz: f64,
    /// Seconds to publish after the bridge's first answer.
    #[arg(long, default_value_t = 10.0, value_name = "S")]
    pub duration: f64,
    /// Seconds to wait for the bridge's first answer.
    #[arg(long, default_value_t = 60.0, value_name = "S")]
    pub discovery_timeout: f64,
    /// The bridge's torque topic, listened to.
    #[arg(long, default_value = "/admittance/external_joint_torques")]
    pub torque_topic: String,
    /// Write the report (every answer included) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    /// Network.
    pub net: NetArgs,
}

/// A failure: exit code (2 usage, 3 bad input file, 1 failure while running) and message.
#[derive(Debug)]
pub struct Failure {
    /// Exit code.
    pub code: u8,
    /// One or two lines.
    pub message: String,
}

fn usage(message: String) -> Failure {
    Failure { code: 2, message }
}
fn input(message: String) -> Failure {
    Failure { code: 3, message }
}
fn failed(message: String) -> Failure {
    Failure { code: 1, message }
}

/// Set by SIGINT or SIGTERM: the loops stop, report and exit 0.
static STOP: AtomicBool = AtomicBool::new(false);

#[cfg(unix)]
extern "C" fn on_signal(_signal: libc::c_int) {
    if STOP.swap(true, Ordering::Relaxed) {
        // A second signal: stop now.
        // SAFETY: _exit is async-signal-safe.
        unsafe { libc::_exit(130) }
    }
}

fn install_stop_handler() {
    #[cfg(unix)]
    // SAFETY: `on_signal` only touches an atomic and calls `_exit`.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
        libc::sigemptyset(&mut action.sa_mask);
        action.sa_flags = libc::SA_RESTART;
        libc::sigaction(libc::SIGINT, &action, std::ptr::null_mut());
        libc::sigaction(libc::SIGTERM, &action, std::ptr::null_mut());
    }
}

/// The distributions known, and whether each uses the 16-byte Gid of Iron and later in
/// its graph messages (`ros_discovery_info`). Data topics are the same on all of them.
const DISTROS: &[(&str, bool)] = &[
    ("galactic", false),
    ("humble", false),
    ("iron", true),
    ("jazzy", true),
    ("kilted", true),
    ("rolling", true),
];

/// Checks `--distro` (or `$ROS_DISTRO`) against the distribution this build speaks.
pub fn check_distro(requested: Option<&str>) -> Result<&'static str, String> {
    let built = ros2_client::COMPILED_ROS_DISTRO.as_str();
    let from_env = std::env::var("ROS_DISTRO").ok().filter(|s| !s.is_empty());
    let (wanted, source) = match (requested, from_env.as_deref()) {
        (Some(d), _) => (d.to_string(), "--distro"),
        (None, Some(d)) => (d.to_string(), "ROS_DISTRO"),
        (None, None) => return Ok(built),
    };
    let Some(&(name, new_gid)) = DISTROS.iter().find(|(n, _)| *n == wanted) else {
        return Err(format!(
            "{source} `{wanted}`: not a ROS 2 distribution this bridge knows ({})",
            DISTROS.iter().map(|d| d.0).collect::<Vec<_>>().join(", ")
        ));
    };
    let built_new_gid = DISTROS.iter().find(|d| d.0 == built).is_some_and(|d| d.1);
    if new_gid != built_new_gid {
        return Err(format!(
            "{source} `{name}`: this build speaks {built}'s graph messages ({}-byte Gid in ros_discovery_info), {name} uses {}-byte ones; rebuild with `--no-default-features --features {}` (crate admittance-ros2)",
            if built_new_gid { 16 } else { 24 },
            if new_gid { 16 } else { 24 },
            if new_gid { "jazzy" } else { "humble" }
        ));
    }
    Ok(name)
}

fn duration(flag: &str, s: f64) -> Result<Duration, Failure> {
    if s.is_finite() && s > 0.0 && s < 1e7 {
        Ok(Duration::from_secs_f64(s))
    } else {
        Err(usage(format!(
            "{flag} {s}: give a positive number of seconds"
        )))
    }
}

fn write_json<T: serde::Serialize>(path: &std::path::Path, value: &T) -> Result<(), Failure> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| failed(format!("{}: {e}", path.display())))?;
    // Atomically, never through a planted link (issue 34).
    admittance_files::write_atomic(path, (text + "\n").as_bytes())
        .map_err(|e| failed(format!("cannot write {}: {e}", path.display())))
}

/// Runs the subcommand.
pub fn run(args: &Ros2Args) -> Result<(), Failure> {
    match &args.command {
        Ros2Command::Bridge(a) => bridge(a),
        Ros2Command::FakeArm(a) => fake_arm(a),
    }
}

fn bridge(a: &BridgeArgs) -> Result<(), Failure> {
    let distro = check_distro(a.net.distro.as_deref()).map_err(usage)?;
    let dds = DdsOptions::from_env(a.net.domain_id, a.net.localhost_only).map_err(usage)?;
    let run_for = a.duration.map(|s| duration("--duration", s)).transpose()?;
    let profile = Profile::resolve(&a.profile).map_err(|e| input(e.to_string()))?;
    let config = BridgeConfig {
        deployment: a.deployment.clone(),
        overrides: a.overrides.clone(),
        profile,
        joints: a.joints.clone(),
        wrench_frame: a.wrench_frame,
    };
    let mut bridge = Bridge::new(&config).map_err(input)?;
    let map = bridge.input_map().clone();
    eprintln!(
        "admittance ros2 bridge: {} joints [{}]; reads {} (best-effort; q = {}, qdot = {}, tau = {}); publishes {} (JointState effort) and {} (WrenchStamped, frame {}){}; domain {}{}, {distro}; loop {:.0} Hz",
        bridge.joint_names().len(),
        bridge.joint_names().join(", "),
        map.topic,
        map.q_field,
        map.qdot_field.as_deref().unwrap_or("differentiated"),
        map.tau_field,
        a.torque_topic,
        a.wrench_topic,
        bridge.wrench_frame_id(),
        a.reference_topic
            .as_ref()
            .map(|t| format!(" and {t} (compliant reference)"))
            .unwrap_or_default()
            + &if bridge.rust_loop().has_contact_floor() {
                format!(" and {} (contact flags)", a.contact_topic)
            } else {
                String::new()
            }
            + &format!(" and {} (status flags)", a.status_topic),
        dds.domain_id,
        if dds.localhost_only { " (localhost only)" } else { "" },
        1.0 / bridge.dt(),
    );
    install_stop_handler();
    let topics = BridgeTopics {
        node_name: a.node_name.clone(),
        torque_topic: a.torque_topic.clone(),
        wrench_topic: a.wrench_topic.clone(),
        reference_topic: a.reference_topic.clone(),
        contact_topic: a.contact_topic.clone(),
        status_topic: a.status_topic.clone(),
        duration: run_for,
    };
    let mut seen = BTreeSet::new();
    let stats = run_bridge(&mut bridge, &dds, &topics, &STOP, |reason, detail| {
        if seen.insert(reason.to_string()) {
            eprintln!("admittance ros2 bridge: skipped a message ({reason}): {detail} (further ones are counted)");
        }
    })
    .map_err(failed)?;
    eprint!("{}", stats.summary());
    if stats.stepped > 10
        && (stats.stamp_rate_hz - stats.loop_rate_hz).abs() > 0.05 * stats.loop_rate_hz
    {
        eprintln!(
            "admittance ros2 bridge: warning: the messages came at {:.1} Hz but the loop runs at {:.1} Hz: set the loop's rate with --set control_rate_hz={:.0}",
            stats.stamp_rate_hz, stats.loop_rate_hz, stats.stamp_rate_hz
        );
    }
    if let Some(path) = &a.stats {
        write_json(path, &stats)?;
    }
    Ok(())
}

fn fake_arm(a: &FakeArmArgs) -> Result<(), Failure> {
    check_distro(a.net.distro.as_deref()).map_err(usage)?;
    let dds = DdsOptions::from_env(a.net.domain_id, a.net.localhost_only).map_err(usage)?;
    let profile = Profile::resolve(&a.profile).map_err(|e| input(e.to_string()))?;
    let topic = crate::bridge::InputMap::from_profile(&profile)
        .map_err(input)?
        .topic;
    let opts = FakeArmOptions {
        topic,
        joints: a.joints.clone(),
        rate_hz: a.rate_hz,
        duration: duration("--duration", a.duration)?,
        torque_topic: a.torque_topic.clone(),
        discovery_timeout: duration("--discovery-timeout", a.discovery_timeout)?,
    };
    install_stop_handler();
    let report = run_fake_arm(&dds, &opts, &STOP).map_err(failed)?;
    eprintln!(
        "admittance ros2 fake-arm: {} messages on {} during discovery ({:.2} s), then {} in the window at {:.1} Hz: {} answered ({:.2} %); round trip median {:.0} us, 99th percentile {:.0} us",
        report.discovery_messages,
        report.topic,
        report.discovery_s,
        report.window_messages,
        report.publish_rate_hz,
        report.window_answered,
        100.0 * report.delivered_share,
        report.round_trip.median_us,
        report.round_trip.p99_us
    );
    if let Some(path) = &a.out {
        write_json(path, &report)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distro_rules() {
        // This build is jazzy (the default feature) unless built with humble.
        let built = ros2_client::COMPILED_ROS_DISTRO.as_str();
        assert_eq!(check_distro(Some(built)).unwrap(), built);
        let e = check_distro(Some("foxy")).unwrap_err();
        assert!(e.contains("--distro `foxy`") && e.contains("humble"), "{e}");
        if built == "jazzy" {
            assert_eq!(check_distro(Some("kilted")).unwrap(), "kilted");
            let e = check_distro(Some("humble")).unwrap_err();
            assert!(e.contains("--features humble"), "{e}");
        }
    }
}
