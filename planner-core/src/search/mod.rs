//! The global search over one form: seeds swept in closed form, near misses moved out of the
//! obstacles they cut, and the best seeds refined by the SQP into the form's outcome.

pub(crate) mod escape;
pub(crate) mod in_plane_geometry;
pub(crate) mod seeds;
pub(crate) mod solve;
pub(crate) mod starts;
pub(crate) mod sweep_plane;
