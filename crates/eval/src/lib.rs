//! The paper's experiment (§4): SCAPE pose deformation of a simplified pose set, v2f and
//! v2v errors, and the method comparison.
