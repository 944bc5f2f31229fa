//! `desal eval`: the paper's experiment (§4) — simplify with each method, carry the
//! simplification to every pose, fit the SCAPE deformation model on the simplified
//! set, deform to every pose and measure v2f/v2v against the ground truth.
