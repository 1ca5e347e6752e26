//! The one seeded generator, defined in `hil-sim` (the simulated tissue and tracker draw from it
//! too) and re-exported here for the analysis and the tests.

pub use hil_sim::random::*;
