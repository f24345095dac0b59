//! Simulator glue: pose input, host views, display channels, scripted flights, other traffic.

pub mod channel;
pub mod flight;
pub mod geo_mapping;
pub mod host_view;
pub mod pose_input;
pub mod terrain_queries;
pub mod traffic;
