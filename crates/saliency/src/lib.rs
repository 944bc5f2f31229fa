//! Stage 2: per-vertex deformation saliency from the fit residuals (paper §3.1).
