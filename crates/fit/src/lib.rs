//! Stage 1: per-part rigid fit of the template onto every pose (paper §3.1, Eq. 1–2).
