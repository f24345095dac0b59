//! The application: the command line and one module per command.

pub mod cli;
pub mod commands;
pub mod failure;
pub mod prepare;
pub mod window;
