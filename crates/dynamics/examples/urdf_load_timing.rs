//! Loading time of large generated URDFs, to check that it grows linearly with the
//! file's size. Prints one line per (shape, size): the median of `REPEATS` loads, the
//! time per link and the ratio to the previous size's time per link (1.0 = linear).
//!
//! Shapes:
//! * `chain`: one serial chain of N revolute links (the tip is the single leaf);
//! * `tree`: a 7-joint arm whose every link carries a long branch (fixed and revolute
//!   joints alternating) hanging off it, N links in all; tip named.
//!
//! Usage: cargo run --release -p admittance-dynamics --example urdf_load_timing -- [SIZES..]
//! (default sizes 2500 5000 10000 20000; REPEATS environment variable, default 3).

use std::fmt::Write as _;
use std::time::Instant;

use admittance_dynamics::Model;

const INERTIAL: &str = r#"<inertial><origin xyz="0 0 0.05" rpy="0 0 0"/><mass value="0.5"/><inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.001"/></inertial>"#;

fn link(out: &mut String, name: &str) {
    let _ = writeln!(out, r#"  <link name="{name}">{INERTIAL}</link>"#);
}

fn joint(out: &mut String, name: &str, kind: &str, parent: &str, child: &str) {
    let _ = writeln!(
        out,
        r#"  <joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/><origin xyz="0 0 0.1" rpy="0 0.1 0"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="2"/></joint>"#
    );
}

/// A chain of `n` links: l0 - l1 - ... (all revolute).
fn chain(n: usize) -> String {
    let mut out = String::from("<?xml version=\"1.0\"?>\n<robot name=\"chain\">\n");
    for i in 0..n {
        link(&mut out, &format!("l{i}"));
        if i > 0 {
            joint(
                &mut out,
                &format!("j{i}"),
                "revolute",
                &format!("l{}", i - 1),
                &format!("l{i}"),
            );
        }
    }
    out.push_str("</robot>\n");
    out
}

/// A 7-joint arm (a0 .. a7, tip a7) with a branch of about n/8 links hanging off each arm
/// link; branch joints alternate fixed and revolute.
fn tree(n: usize) -> String {
    let mut out = String::from("<?xml version=\"1.0\"?>\n<robot name=\"tree\">\n");
    let per_branch = (n / 8).saturating_sub(1);
    for a in 0..8 {
        link(&mut out, &format!("a{a}"));
        if a > 0 {
            joint(
                &mut out,
                &format!("arm{a}"),
                "revolute",
                &format!("a{}", a - 1),
                &format!("a{a}"),
            );
        }
        for b in 0..per_branch {
            let name = format!("b{a}_{b}");
            link(&mut out, &name);
            let parent = if b == 0 {
                format!("a{a}")
            } else {
                format!("b{a}_{}", b - 1)
            };
            let kind = if b % 2 == 0 { "fixed" } else { "revolute" };
            joint(&mut out, &format!("jb{a}_{b}"), kind, &parent, &name);
        }
    }
    out.push_str("</robot>\n");
    out
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let sizes = if sizes.is_empty() {
        vec![2500, 5000, 10000, 20000]
    } else {
        sizes
    };
    let repeats: usize = std::env::var("REPEATS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(3)
        .max(1);
    for (shape, make, tip) in [
        ("chain", chain as fn(usize) -> String, None),
        ("tree", tree as fn(usize) -> String, Some("a7")),
    ] {
        let mut previous: Option<f64> = None;
        for &n in &sizes {
            let text = make(n);
            let mut times = Vec::new();
            for _ in 0..repeats {
                let start = Instant::now();
                let model =
                    Model::from_urdf_str(&text, shape, None, tip).unwrap_or_else(|e| panic!("{e}"));
                times.push(start.elapsed().as_secs_f64());
                std::hint::black_box(model);
            }
            let t = median(times);
            let per_link = t / n as f64;
            let ratio = previous.map_or(String::from("-"), |p| format!("{:.2}", per_link / p));
            println!(
                "{shape:<6} {n:>7} links {:>9} bytes  median {:>9.4} s  {:>8.3} us/link  per-link ratio to previous {ratio}",
                text.len(),
                t,
                per_link * 1e6
            );
            previous = Some(per_link);
        }
    }
}
