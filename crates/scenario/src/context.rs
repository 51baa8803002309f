//! The context of reading one variant: its source, for errors located at their key.

use admittance_control::ConfigError;

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

    /// A controller or admittance configuration error, located at its key in the scenario
    /// (`k2[1]` of `[controller.neural]` is written at `controller.neural.k2`).
    pub fn config_err(&self, section: &str, e: &ConfigError) -> ScenarioError {
        let key: String = e.key.split('[').next().unwrap_or("").to_string();
        let path = if key.is_empty() {
            section.to_string()
        } else {
            format!("{section}.{key}")
        };
        let hint = e
            .hint
            .as_deref()
            .unwrap_or("change the value so that it meets the stated bound (the file or --set)");
        let mut err = self.err(&path, e.message.clone(), Some(hint));
        if e.key.contains('[') {
            err.key = Some(format!("{section}.{}", e.key));
        }
        err
    }
}
