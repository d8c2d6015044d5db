//! Solver settings, a plain struct shared by every [`super::ConeSolver`].

/// Solver settings (a plain struct; start from `SolveSettings::default()`).
#[derive(Clone, Debug, PartialEq)]
pub struct SolveSettings {
    /// Maximum number of interior-point iterations.
    pub max_iter: u32,
    /// Wall-clock limit in seconds (`None`: no limit).
    pub time_limit: Option<f64>,
    /// Print the solver's progress.
    pub verbose: bool,
    /// Absolute duality-gap tolerance.
    pub tol_gap_abs: f64,
    /// Relative duality-gap tolerance.
    pub tol_gap_rel: f64,
    /// Feasibility tolerance.
    pub tol_feas: f64,
    /// Absolute infeasibility tolerance.
    pub tol_infeas_abs: f64,
    /// Relative infeasibility tolerance.
    pub tol_infeas_rel: f64,
    /// Let the solver split PSD cones with a chordal sparsity pattern.
    pub chordal_decomposition: bool,
    /// Let the solver rescale the data.
    pub equilibrate: bool,
    /// Sparse LDL factorization used for the KKT systems.
    pub linear_solver: LinearSolver,
    /// Threads of the KKT factorization: 1 (the default) factors sequentially,
    /// so the same problem gives the same bits on every machine; 0 lets the
    /// solver use every core, whose count then changes the rounding.
    pub threads: u32,
}

/// The sparse LDL factorization of the interior-point KKT systems.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinearSolver {
    /// faer's supernodal LDL (fast on the dense blocks PSD cones create).
    Faer,
    /// QDLDL (scalar, simplicial).
    Qdldl,
}

impl LinearSolver {
    /// faer's LDL on 64-bit targets; QDLDL on 32-bit ones (the wasm32
    /// playground), where Clarabel's faer does not build.
    #[cfg(target_pointer_width = "64")]
    pub const DEFAULT: LinearSolver = LinearSolver::Faer;
    /// faer's LDL on 64-bit targets; QDLDL on 32-bit ones (the wasm32
    /// playground), where Clarabel's faer does not build.
    #[cfg(not(target_pointer_width = "64"))]
    pub const DEFAULT: LinearSolver = LinearSolver::Qdldl;
}

impl Default for SolveSettings {
    fn default() -> Self {
        SolveSettings {
            max_iter: 200,
            time_limit: None,
            verbose: false,
            tol_gap_abs: 1e-8,
            tol_gap_rel: 1e-8,
            tol_feas: 1e-8,
            tol_infeas_abs: 1e-8,
            tol_infeas_rel: 1e-8,
            chordal_decomposition: true,
            equilibrate: true,
            linear_solver: LinearSolver::DEFAULT,
            threads: 1,
        }
    }
}
