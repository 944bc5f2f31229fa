//! Software rendering of a mesh with a per-vertex or per-face scalar to an RGBA image
//! (heat maps for saliency, face areas and errors).
