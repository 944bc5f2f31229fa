//! Stage 4: greedy least-distance mapping of simplified vertices to original vertex
//! indices, and applying the map to every pose (paper §3.2).
