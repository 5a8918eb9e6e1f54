//! The TPMS library of the Cesogen paper (Table 2), period 1.
