//! Why code generation failed.

use crate::tables::TablesError;
use std::fmt;
use tsf_lang::spec::Emit;

/// What keeps a design from becoming code.
#[derive(Debug, Clone, PartialEq)]
pub enum CodegenError {
    /// The tables of the design cannot be built.
    Tables(TablesError),
    /// No backend is registered for an `emit` target.
    NoBackend(Emit),
    /// The controller's name would collide with support code of a language.
    ReservedName {
        /// The controller name.
        name: String,
        /// The language, e.g. `C`.
        language: &'static str,
    },
    /// A sensor module was asked for but the design has no aperiodic trigger.
    NoSensor,
    /// An adaptive spec asks for `precision f32`: the law is generated in f64 only.
    AdaptivePrecision,
    /// The adaptive design was refused (`adaptive-refused`): no code.
    AdaptiveRefused,
    /// `emit c(style = straight)` for an observer-based design: its C step
    /// is table-driven only.
    ObserverStraight,
    /// An observer-based design with a feature its generated step does not
    /// cover (what).
    ObserverUnsupported(&'static str),
    /// The generated text of a language does not parse (a generator bug).
    Unparsable {
        /// The language, e.g. `Rust`.
        language: &'static str,
        /// The parser's message.
        reason: String,
    },
}

impl fmt::Display for CodegenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CodegenError::Tables(e) => e.fmt(f),
            CodegenError::NoBackend(target) => write!(
                f,
                "internal error: no code generator is registered for `emit {target:?}`"
            ),
            CodegenError::ReservedName { name, language } => write!(
                f,
                "the controller name `{name}` is reserved in generated {language} (the runtime's symbols start with `tsf_`): rename the controller"
            ),
            CodegenError::NoSensor => {
                f.write_str("internal error: no aperiodic trigger: no sensor module")
            }
            CodegenError::AdaptivePrecision => f.write_str(
                "the adaptive law is generated in f64 only (docs/limits.md): remove `precision f32`",
            ),
            CodegenError::AdaptiveRefused => f.write_str(
                "the adaptive design was refused (`adaptive-refused`): no code is generated",
            ),
            CodegenError::ObserverStraight => f.write_str(
                "the observer-based controller's C step is table-driven only: write `emit c(style = table);` or `emit c;` (docs/limits.md)",
            ),
            CodegenError::ObserverUnsupported(what) => write!(
                f,
                "the observer-based controller is not generated with {what} (docs/limits.md)"
            ),
            CodegenError::Unparsable { language, reason } => write!(
                f,
                "internal error: generated {language} does not parse: {reason}"
            ),
        }
    }
}

impl std::error::Error for CodegenError {}

impl From<TablesError> for CodegenError {
    fn from(e: TablesError) -> Self {
        CodegenError::Tables(e)
    }
}
