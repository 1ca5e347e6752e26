//! The local optimiser: one form's problem (variables, objective, constraints and their exact
//! derivatives), the feasible-path SQP that solves it and the active-set QP behind each step.

pub(crate) mod basins;
pub(crate) mod linalg;
#[cfg(test)]
mod near_tests;
pub(crate) mod objective;
pub(crate) mod problem;
pub(crate) mod qp;
pub(crate) mod sqp;
