//! The one error type of the pipeline, shared by the CLI, the build-script
//! [`crate::Builder`], the simulator and the benches; its kind decides the
//! exit code.

/// What kind of failure an [`Error`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The spec is invalid or cannot be used this way (exit 1).
    Spec,
    /// Bad command-line values or an I/O failure (exit 2).
    Usage,
    /// Infeasible, not certified, or no code could be generated for the
    /// certified design (exit 3).
    NotCertified,
}

/// A failure with a message for the user.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error {
    /// Kind.
    pub kind: ErrorKind,
    /// What went wrong (rendered diagnostics for spec errors).
    pub message: String,
}

impl Error {
    /// A spec error.
    pub fn spec(message: impl Into<String>) -> Self {
        Error {
            kind: ErrorKind::Spec,
            message: message.into(),
        }
    }

    /// Something the simulator or a backend does not support (a spec error).
    pub fn unsupported(message: impl Into<String>) -> Self {
        Self::spec(message)
    }

    /// A numeric failure of the integration (a spec error).
    pub fn numeric(message: impl Into<String>) -> Self {
        Self::spec(message)
    }

    /// A usage or I/O error.
    pub fn usage(message: impl Into<String>) -> Self {
        Error {
            kind: ErrorKind::Usage,
            message: message.into(),
        }
    }

    /// No certified design (infeasible, refused, or code generation failed).
    pub fn not_certified(message: impl Into<String>) -> Self {
        Error {
            kind: ErrorKind::NotCertified,
            message: message.into(),
        }
    }

    /// The process exit code: 1 spec, 2 usage or I/O, 3 not certified.
    pub fn exit_code(&self) -> u8 {
        match self.kind {
            ErrorKind::Spec => 1,
            ErrorKind::Usage => 2,
            ErrorKind::NotCertified => 3,
        }
    }
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Error {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_codes_follow_the_documented_table() {
        assert_eq!(Error::spec("x").exit_code(), 1);
        assert_eq!(Error::numeric("x").exit_code(), 1);
        assert_eq!(Error::usage("x").exit_code(), 2);
        assert_eq!(Error::not_certified("x").exit_code(), 3);
        assert_eq!(Error::usage("boom").to_string(), "boom");
    }
}
