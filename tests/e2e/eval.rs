//! `desal eval` end to end.
