//! Stage 3: saliency-weighted quadric edge collapse (paper §3.1, Eq. 3–5; Garland and
//! Heckbert 1997).
