//! Mesh validators: watertightness, manifoldness, Euler characteristic, volume, area.
