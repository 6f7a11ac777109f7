//! anima's integration tests live in `tests/`: one test binary (`tests/main.rs`) with a module per
//! subject. This library is empty on purpose; shared helpers go here when tests need them.
