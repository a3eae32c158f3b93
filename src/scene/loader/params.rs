//! STUB: parameter lists with used-tracking.
/// A parameter list as written in the file, with each parameter's location; reading a
/// parameter marks it used, and `check_unused` reports the ones nobody read.
#[derive(Clone, Debug, Default)]
pub struct ParamSet {}
