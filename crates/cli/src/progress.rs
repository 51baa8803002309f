//! Progress display on stderr (indicatif): a bar for the stages of a run, a spinner for
//! single long steps. Shown only when stderr is a terminal, `CI` is not set and `--quiet` is
//! not given, and only once the work has taken longer than a second.

use std::io::IsTerminal;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use admittance_scenario::{Progress, ProgressFn, Stage};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Whether progress should be drawn: not `--quiet`, not in CI (`CI` set) and stderr is a
/// terminal.
pub fn wanted(quiet: bool) -> bool {
    !quiet && std::env::var_os("CI").is_none() && std::io::stderr().is_terminal()
}

/// Work shorter than this shows no progress.
const DELAY: Duration = Duration::from_secs(1);

/// A stage's name for people: `TrainingData` -> `training data` (any stage, including
/// ones added later, is named from its variant name).
pub fn stage_name(stage: Stage) -> String {
    let debug = format!("{stage:?}");
    let mut out = String::new();
    for (k, c) in debug.chars().enumerate() {
        if c.is_uppercase() && k > 0 {
            out.push(' ');
        }
        out.extend(c.to_lowercase());
    }
    out
}

/// What a stage is doing, for people: the known stages described, any other named from its
/// variant name.
pub fn stage_label(stage: Stage) -> String {
    match stage {
        Stage::Simulate => "simulating the closed loop".into(),
        Stage::TrainingData => "simulating free motion for the training data".into(),
        Stage::Train => "training the observer network (can take minutes)".into(),
        #[allow(unreachable_patterns)]
        other => stage_name(other),
    }
}

/// The bar of a stage counted in units, and the spinner of one counted in a single phase.
fn bar_style() -> ProgressStyle {
    ProgressStyle::with_template("{msg} [{wide_bar}] {percent:>3}% {elapsed} (eta {eta})")
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ")
}

fn spinner_style() -> ProgressStyle {
    ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
        .unwrap_or_else(|_| ProgressStyle::default_spinner())
}

struct State {
    /// (variant, stage) of the stage shown.
    key: Option<(String, Stage)>,
    /// Index and count of the variant running (from the runner's per-variant callback).
    variant: (usize, usize),
    shown: bool,
}

/// The progress bar of `admittance run`.
pub struct RunProgress {
    bar: ProgressBar,
    started: Instant,
    state: Mutex<State>,
}

impl RunProgress {
    /// A bar, hidden until the run has taken a second.
    pub fn new() -> Arc<Self> {
        let bar = ProgressBar::with_draw_target(Some(1), ProgressDrawTarget::hidden());
        bar.set_style(bar_style());
        let me = Arc::new(Self {
            bar,
            started: Instant::now(),
            state: Mutex::new(State {
                key: None,
                variant: (0, 1),
                shown: false,
            }),
        });
        // A stage that reports rarely (training: at its start and end) must not leave the
        // terminal silent: show the bar once due, and keep its clock turning.
        let weak = Arc::downgrade(&me);
        std::thread::spawn(move || {
            std::thread::sleep(DELAY);
            if let Some(me) = weak.upgrade() {
                if let Ok(mut s) = me.state.lock() {
                    // Nothing to show before the first report (it shows itself then).
                    if s.key.is_some() {
                        me.show_if_due(&mut s);
                    }
                }
            }
        });
        me
    }

    fn show_if_due(&self, state: &mut State) {
        if !state.shown && !self.bar.is_finished() && self.started.elapsed() >= DELAY {
            state.shown = true;
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.bar.enable_steady_tick(Duration::from_millis(200));
        }
    }

    /// The runner started variant `k` of `total`.
    pub fn variant_started(&self, k: usize, total: usize) {
        if let Ok(mut s) = self.state.lock() {
            s.variant = (k, total);
        }
    }

    /// A progress report of the runner.
    pub fn update(&self, p: Progress<'_>) {
        let Ok(mut s) = self.state.lock() else { return };
        let same = s
            .key
            .as_ref()
            .is_some_and(|(v, st)| v == p.variant && *st == p.stage);
        if !same {
            s.key = Some((p.variant.to_string(), p.stage));
            let (k, n) = s.variant;
            let prefix = if n > 1 {
                format!("[{}/{}] ", k + 1, n)
            } else {
                String::new()
            };
            // A stage of one phase has no fraction to show: a spinner and its clock.
            self.bar.set_style(if p.total > 1 {
                bar_style()
            } else {
                spinner_style()
            });
            self.bar.set_length(p.total.max(1));
            self.bar.reset();
            self.bar
                .set_message(format!("{prefix}{}: {}", p.variant, stage_label(p.stage)));
        }
        self.bar.set_position(p.done.min(p.total));
        self.show_if_due(&mut s);
    }

    /// The callback to hand to the runner.
    pub fn callback(self: &Arc<Self>) -> ProgressFn {
        let me = Arc::clone(self);
        Arc::new(move |p| me.update(p))
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// A spinner with a message for one long step; hidden unless `enabled`, and drawn only
/// after a second. Cleared when dropped.
pub struct Spinner {
    bar: Option<ProgressBar>,
}

impl Spinner {
    /// Starts a spinner (or nothing when `enabled` is false).
    pub fn start(enabled: bool, message: impl Into<String>) -> Self {
        if !enabled {
            return Self { bar: None };
        }
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        bar.set_style(spinner_style());
        bar.set_message(message.into());
        let shown = bar.clone();
        // Show it after the delay (unless finished by then), then keep it turning.
        std::thread::spawn(move || {
            std::thread::sleep(DELAY);
            if !shown.is_finished() {
                shown.set_draw_target(ProgressDrawTarget::stderr());
                shown.enable_steady_tick(Duration::from_millis(120));
            }
        });
        Self { bar: Some(bar) }
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_names() {
        assert_eq!(stage_name(Stage::Simulate), "simulate");
        assert_eq!(stage_name(Stage::TrainingData), "training data");
        assert_eq!(stage_name(Stage::Train), "train");
        assert!(stage_label(Stage::Train).starts_with("training"));
    }
}
