use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use faer::sparse::SparseColMat;

use super::OutputError;

/// Writes every stored entry of `a` as a Matrix Market `coordinate real general` file
/// (1-based indices, 17 significant digits so that the values round-trip exactly).
pub fn write_matrix_market(path: &Path, a: &SparseColMat<usize, f64>) -> Result<(), OutputError> {
    let io = |source| OutputError::Io {
        path: path.to_owned(),
        source,
    };
    let (symbolic, values) = a.parts();
    let mut w = BufWriter::new(File::create(path).map_err(io)?);
    writeln!(w, "%%MatrixMarket matrix coordinate real general").map_err(io)?;
    writeln!(
        w,
        "{} {} {}",
        symbolic.nrows(),
        symbolic.ncols(),
        values.len()
    )
    .map_err(io)?;
    let col_ptr = symbolic.col_ptr();
    let row_idx = symbolic.row_idx();
    for j in 0..symbolic.ncols() {
        for p in col_ptr[j]..col_ptr[j + 1] {
            writeln!(w, "{} {} {:.17e}", row_idx[p] + 1, j + 1, values[p]).map_err(io)?;
        }
    }
    w.flush().map_err(io)
}
