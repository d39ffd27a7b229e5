//! Node parameters: typed declarations, ROS 2 params files, and resolution in rcl precedence order.

mod declaration;
mod file;
mod resolve;
mod value;
mod watch;

pub use declaration::{set_default, ParamDecl, ValueProblem};
pub use file::{
    parse_params_file, pattern_matches_node, read_params_file, ParamsFileError, ParamsFileSection,
};
pub(crate) use resolve::problem_error;
pub use resolve::{ParamError, ParamSource, Parameters, ResolvedParam, USE_SIM_TIME};
pub use value::{ParamKind, ParamType, ParamValue};
pub use watch::ParamWatch;
