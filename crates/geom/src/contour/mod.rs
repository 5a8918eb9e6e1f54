//! Streaming, watertight marching cubes with capped domain faces.
