//! Empty: every workspace member depends on this package so that its dependencies are built
//! with the same features whichever members are selected (see Cargo.toml).
