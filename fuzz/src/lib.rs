//! The bodies of the file-parser fuzz targets (`fuzz_targets/`), in one file that the replay
//! test (`tests/tests/fuzz_corpus.rs`) compiles too.
pub mod bodies;
