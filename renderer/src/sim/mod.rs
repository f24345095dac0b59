//! Simulator glue: pose input, host views, display channels, scripted flights, other traffic, the sun's clock.

pub mod channel;
pub mod flight;
pub mod geo_mapping;
pub mod host_view;
pub mod pose_input;
pub mod sun_clock;
pub mod terrain_queries;
pub mod traffic;
