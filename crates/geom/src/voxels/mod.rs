//! Voxel images as cell sources: a NumPy `.npy` file or raw bytes with a given shape, holding
//! occupancy (a CT scan's grey values) or signed distance, read into a [`VoxelImage`] and
//! turned into a periodic field ([`VoxelField`]) that a symmetric cell is fitted to.
//!
//! Conventions (docs/manifest.md, "Voxel cells"):
//! - Array index `[i, j, k]` is voxel `i` along x, `j` along y, `k` along z, whatever the
//!   file's memory order: a C-order `.npy` is transposed on reading, a Fortran-order one is
//!   read as is, and a raw file is x fastest, then y, then z.
//! - The image spans the cell `[-½, ½]³` (period 1): voxel `i` of `n` is centred at
//!   `x = (i + ½)/n − ½`, and between centres the field is trilinear, wrapping around the cell
//!   faces, so the field repeats with period 1 and is continuous across the faces.
//! - The field is negative inside. Occupancy `v` with threshold `t` becomes
//!   `(t − v)/(max − min) · h` with `h = 1/max(nx, ny, nz)` the voxel size in cell units, about a
//!   signed distance near a sharp edge; a distance image is taken as it is, in cell units.
//!
//! Invariants: no input panics or allocates more than its own size allows (the shape must
//! match the bytes there are before anything is allocated); every value is finite, and an
//! error names the voxel `(i, j, k)` that is not.

mod field;
mod npy;

use thiserror::Error;

pub use field::VoxelField;

/// The number types a voxel file may hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoxelType {
    U8,
    U16,
    I16,
    F32,
    F64,
}

impl VoxelType {
    /// The names a manifest gives them (NumPy's), in the order they are documented.
    pub const NAMES: [(&'static str, VoxelType); 5] = [
        ("uint8", VoxelType::U8),
        ("uint16", VoxelType::U16),
        ("int16", VoxelType::I16),
        ("float32", VoxelType::F32),
        ("float64", VoxelType::F64),
    ];

    pub fn name(self) -> &'static str {
        match self {
            VoxelType::U8 => "uint8",
            VoxelType::U16 => "uint16",
            VoxelType::I16 => "int16",
            VoxelType::F32 => "float32",
            VoxelType::F64 => "float64",
        }
    }

    pub fn size(self) -> usize {
        match self {
            VoxelType::U8 => 1,
            VoxelType::U16 | VoxelType::I16 => 2,
            VoxelType::F32 => 4,
            VoxelType::F64 => 8,
        }
    }

    fn decode(self, b: &[u8], big_endian: bool) -> f64 {
        let mut a = [0u8; 8];
        a[..b.len()].copy_from_slice(b);
        if big_endian {
            a[..b.len()].reverse();
        }
        match self {
            VoxelType::U8 => f64::from(a[0]),
            VoxelType::U16 => f64::from(u16::from_le_bytes([a[0], a[1]])),
            VoxelType::I16 => f64::from(i16::from_le_bytes([a[0], a[1]])),
            VoxelType::F32 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            VoxelType::F64 => f64::from_le_bytes(a),
        }
    }
}

/// Why a voxel file could not be read; the caller names the file.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum VoxelError {
    #[error("not a NumPy .npy file: it does not begin with `\\x93NUMPY`")]
    NotNpy,
    #[error("malformed .npy header: {0}")]
    NpyHeader(String),
    #[error(
        "unsupported .npy dtype `{0}`: expected uint8, uint16, int16, float32 or float64 \
         (`|u1`, `<u2`, `<i2`, `<f4`, `<f8`, either byte order)"
    )]
    NpyType(String),
    #[error("header says shape {0} but a 3D image is needed")]
    NotThreeD(String),
    #[error("shape {0} has no voxels")]
    NoVoxels(String),
    #[error("file has {have} bytes of data, shape {shape} of {dtype} needs {need}")]
    Size {
        have: usize,
        need: usize,
        shape: String,
        dtype: &'static str,
    },
    #[error("voxel ({}, {}, {}) is {value}: every value must be finite", .voxel[0], .voxel[1], .voxel[2])]
    NonFinite { voxel: [usize; 3], value: f64 },
    #[error("every voxel is {0}: the image has no surface to fit")]
    Uniform(f64),
}

/// A 3D image, `values[(k · ny + j) · nx + i]` for voxel `(i, j, k)`.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelImage {
    pub shape: [usize; 3],
    pub values: Vec<f64>,
}

/// How to read an image's values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VoxelValues {
    /// Inside where the value exceeds the threshold (`None`: halfway between the image's
    /// least and greatest value).
    Occupancy { threshold: Option<f64> },
    /// Signed distance in cell units, negative inside.
    Distance,
}

/// `(32, 32)`, as NumPy shows a shape.
fn show_shape(shape: &[u64]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(u64::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Reads a NumPy `.npy` file of a 3D array.
pub fn read_npy(bytes: &[u8]) -> Result<VoxelImage, VoxelError> {
    let header = npy::header(bytes)?;
    let &[a, b, c] = header.shape.as_slice() else {
        return Err(VoxelError::NotThreeD(show_shape(&header.shape)));
    };
    let data = &bytes[header.data_start.min(bytes.len())..];
    decode(
        data,
        [a, b, c],
        header.dtype,
        header.big_endian,
        header.fortran_order,
    )
}

/// Reads raw voxels: `shape = [nx, ny, nz]`, x fastest, of `dtype` in the given byte order.
pub fn read_raw(
    bytes: &[u8],
    shape: [u64; 3],
    dtype: VoxelType,
    big_endian: bool,
) -> Result<VoxelImage, VoxelError> {
    decode(bytes, shape, dtype, big_endian, true)
}

/// The image of `data`, x fastest when `x_fastest` (Fortran order), else z fastest (C order).
fn decode(
    data: &[u8],
    shape: [u64; 3],
    dtype: VoxelType,
    big_endian: bool,
    x_fastest: bool,
) -> Result<VoxelImage, VoxelError> {
    let shown = show_shape(&shape);
    let count = shape
        .iter()
        .try_fold(1u64, |acc, &n| acc.checked_mul(n))
        .and_then(|n| usize::try_from(n).ok());
    let need = count.and_then(|n| n.checked_mul(dtype.size()));
    let (Some(count), Some(need)) = (count, need) else {
        return Err(VoxelError::Size {
            have: data.len(),
            need: usize::MAX,
            shape: shown,
            dtype: dtype.name(),
        });
    };
    if count == 0 {
        return Err(VoxelError::NoVoxels(shown));
    }
    if data.len() != need {
        return Err(VoxelError::Size {
            have: data.len(),
            need,
            shape: shown,
            dtype: dtype.name(),
        });
    }
    // Fits in usize: their product does.
    let [nx, ny, nz] = shape.map(|n| n as usize);
    let mut values = vec![0.0; count];
    for (n, raw) in data.chunks_exact(dtype.size()).enumerate() {
        let (i, j, k) = if x_fastest {
            (n % nx, n / nx % ny, n / (nx * ny))
        } else {
            (n / (ny * nz), n / nz % ny, n % nz)
        };
        let value = dtype.decode(raw, big_endian);
        if !value.is_finite() {
            return Err(VoxelError::NonFinite {
                voxel: [i, j, k],
                value,
            });
        }
        values[(k * ny + j) * nx + i] = value;
    }
    Ok(VoxelImage {
        shape: [nx, ny, nz],
        values,
    })
}

impl VoxelImage {
    /// The image's values as a field, negative inside (see the module's conventions).
    pub fn field(&self, values: VoxelValues) -> Result<VoxelField, VoxelError> {
        let samples = match values {
            VoxelValues::Distance => self.values.clone(),
            VoxelValues::Occupancy { threshold } => {
                let (lo, hi) = self
                    .values
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                        (lo.min(v), hi.max(v))
                    });
                if hi <= lo {
                    return Err(VoxelError::Uniform(lo));
                }
                let t = threshold.unwrap_or(0.5 * (lo + hi));
                let voxel = 1.0 / self.shape.iter().copied().max().unwrap_or(1) as f64;
                let scale = voxel / (hi - lo);
                self.values.iter().map(|v| (t - v) * scale).collect()
            }
        };
        Ok(VoxelField::new(self.shape, samples))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
        let dict = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
            if fortran { "True" } else { "False" }
        );
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend((dict.len() as u16).to_le_bytes());
        out.extend(dict.as_bytes());
        out.extend(data);
        out
    }

    /// Voxel (i, j, k) holds 100 i + 10 j + k: C order (k fastest) and Fortran order (i
    /// fastest) and raw (i fastest) all give the same image.
    #[test]
    fn c_fortran_and_raw_orders_index_voxels_alike() {
        let shape = [2usize, 3, 4];
        let value = |i: usize, j: usize, k: usize| (100 * i + 10 * j + k) as u16;
        let mut c = Vec::new();
        for i in 0..2 {
            for j in 0..3 {
                for k in 0..4 {
                    c.extend(value(i, j, k).to_le_bytes());
                }
            }
        }
        let mut f = Vec::new();
        for k in 0..4 {
            for j in 0..3 {
                for i in 0..2 {
                    f.extend(value(i, j, k).to_le_bytes());
                }
            }
        }
        let from_c = read_npy(&npy("<u2", false, "(2, 3, 4)", &c)).expect("C order");
        let from_f = read_npy(&npy("<u2", true, "(2, 3, 4)", &f)).expect("Fortran order");
        let raw = read_raw(&f, [2, 3, 4], VoxelType::U16, false).expect("raw");
        assert_eq!(from_c, from_f);
        assert_eq!(from_c, raw);
        assert_eq!(from_c.shape, shape);
        assert_eq!(from_c.values[(3 * 3 + 2) * 2 + 1], 123.0);
        let big: Vec<u8> = f.chunks(2).flat_map(|p| [p[1], p[0]]).collect();
        assert_eq!(read_raw(&big, [2, 3, 4], VoxelType::U16, true), Ok(raw));
    }

    #[test]
    fn errors_say_what_is_wrong_and_where() {
        let e = read_npy(&npy("<f4", false, "(32, 32)", &[0; 4096])).expect_err("2D");
        assert_eq!(
            e.to_string(),
            "header says shape (32, 32) but a 3D image is needed"
        );
        let e = read_npy(&npy("|u1", false, "(32, 32, 32)", &[0; 32767])).expect_err("short");
        assert_eq!(
            e.to_string(),
            "file has 32767 bytes of data, shape (32, 32, 32) of uint8 needs 32768"
        );
        let mut data: Vec<u8> = [0.0f32; 8].iter().flat_map(|v| v.to_le_bytes()).collect();
        data[4 * 5..4 * 6].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = read_raw(&data, [2, 2, 2], VoxelType::F32, false).expect_err("nan");
        assert_eq!(
            e.to_string(),
            "voxel (1, 0, 1) is NaN: every value must be finite"
        );
        let huge = read_raw(&[], [u64::MAX, 2, 2], VoxelType::U8, false).expect_err("huge");
        assert!(matches!(huge, VoxelError::Size { .. }));
        assert_eq!(
            read_raw(&[], [0, 2, 2], VoxelType::U8, false),
            Err(VoxelError::NoVoxels("(0, 2, 2)".into()))
        );
        let flat = read_raw(&[7; 8], [2, 2, 2], VoxelType::U8, false).expect("flat");
        assert_eq!(
            flat.field(VoxelValues::Occupancy { threshold: None })
                .map(|_| ()),
            Err(VoxelError::Uniform(7.0))
        );
    }
}
