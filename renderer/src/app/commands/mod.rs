//! One module per `aerie` command. Each returns the CLI's
//! [`Failure`](crate::app::failure::Failure): exit 2 for bad input, 1 at run time.

pub mod bake;
pub mod bench;
pub mod flight_files;
pub mod fly;
pub mod fly_no_draw;
pub mod gen_dem;
pub mod import;
pub mod import_imagery;
pub mod info;
pub mod input_args;
pub mod listen;
pub mod render;
pub mod replay;
pub mod run;
