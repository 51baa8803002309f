//! The context of reading one variant: its source, for errors located at their key.

use admittance_control::ConfigError;
use admittance_loop::LoopError;
use admittance_sim::SimError;

use crate::error::ScenarioError;
use crate::source::ScenarioSource;

/// A scenario's reading of one variant, with its source for located errors.
pub(crate) struct Ctx<'a> {
    pub source: &'a ScenarioSource,
    pub variant: Option<&'a str>,
}

impl Ctx<'_> {
    pub fn err(&self, key: &str, message: impl Into<String>, hint: Option<&str>) -> ScenarioError {
        self.source
            .error_at(key, self.variant, message, hint.map(String::from))
    }

    /// A bad setting (its key dotted from the scenario's root), located where the value
    /// that variant sees is written.
    pub fn setting_err(&self, e: &ConfigError) -> ScenarioError {
        let hint = e
            .hint
            .as_deref()
            .unwrap_or("change the value so that it meets the stated bound (the file or --set)");
        self.err(&e.key, e.message.clone(), Some(hint))
    }

    /// A component's bad setting, its key relative to the component's table `section`
    /// (`k2[1]` of `[controller.neural]` is written at `controller.neural.k2`).
    pub fn config_err(&self, section: &str, e: &ConfigError) -> ScenarioError {
        self.setting_err(&e.clone().within(section))
    }

    /// A loop error at the same setting, in the scenario's vocabulary.
    pub fn loop_err(&self, e: LoopError) -> ScenarioError {
        self.setting_err(&crate::spec::loop_problem(e))
    }

    /// A simulator error: a bad setting at its key under `[plant]`, anything else at the
    /// plant's table.
    pub fn plant_err(&self, e: SimError) -> ScenarioError {
        match e {
            SimError::Setting(s) => self.config_err("plant", &s),
            other => self.err("plant", other.to_string(), None),
        }
    }
}
