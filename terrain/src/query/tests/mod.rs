//! Tests of the query service against a brute-force oracle (`oracle.rs`): hand-made cases
//! (`cases.rs`), the embedded DEM (`dem.rs`), random small grids (`props.rs`) and sources
//! that withhold tiles (`pending.rs`).

mod cases;
mod dem;
mod oracle;
mod pending;
mod props;
