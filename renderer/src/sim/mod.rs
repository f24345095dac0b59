//! Simulator glue: pose input, host views, display channels, scripted flights.

pub mod channel;
pub mod flight;
pub mod host_view;
pub mod pose_input;
pub mod terrain_queries;
