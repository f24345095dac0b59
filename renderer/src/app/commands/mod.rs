//! One module per `aerie` command. Each returns the CLI's
//! [`Failure`](crate::app::failure::Failure): exit 2 for bad input, 1 at run time.

pub mod bake;
pub mod bench;
pub mod fly;
pub mod gen_dem;
pub mod listen;
pub mod render;
pub mod replay;
pub mod run;

/// Kept for the commands that import it from here (`run --stats`, `listen --record`): refuses
/// an output file whose folder does not exist. New code imports [`crate::app::out_path`].
pub(crate) use crate::app::out_path::require_out_folder as check_out_folder;
