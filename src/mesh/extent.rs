//! What the positions of every node of a body give: its bounding box, its centroid and radius
//! about it, and three nodes far apart. A rank of a distributed run keeps the coordinates of
//! the nodes it reads only ([`super::NodeCoords`]), so rank 0 measures these on the whole body
//! before the partition and every rank keeps them ([`super::RankPart`]).

use serde::{Deserialize, Serialize};

use super::Dim;

/// The extent of a body's nodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyExtent {
    /// The bounding box `(min, max)` of the nodes.
    pub low: [f64; 3],
    pub high: [f64; 3],
    /// The mean of the nodes' positions.
    pub centroid: [f64; 3],
    /// The largest distance of a node from the centroid.
    pub radius: f64,
    /// Nodes far apart, the pins a body without supports gets
    /// (`crate::elastic::ElasticProblem`): the farthest from the centroid, the farthest from
    /// that one, and in 3D the farthest from the line through both. Each maximizes a convex
    /// function of the position, so it is a vertex of the nodes' convex hull, a node of the
    /// body's boundary.
    pub far_apart: Vec<usize>,
}

impl BodyExtent {
    /// The extent of the nodes at `coords` (in `dim` dimensions; `z = 0` in 2D).
    pub fn of(coords: &[[f64; 3]], dim: Dim) -> Self {
        let mut low = [f64::INFINITY; 3];
        let mut high = [f64::NEG_INFINITY; 3];
        for x in coords {
            for k in 0..3 {
                low[k] = low[k].min(x[k]);
                high[k] = high[k].max(x[k]);
            }
        }
        let n = coords.len() as f64;
        let centroid: [f64; 3] =
            std::array::from_fn(|k| coords.iter().map(|x| x[k]).sum::<f64>() / n);
        let radius = (coords.iter())
            .map(|x| distance(x, &centroid))
            .fold(0.0, f64::max);
        Self {
            low,
            high,
            centroid,
            radius,
            far_apart: far_apart_nodes(coords, &centroid, dim),
        }
    }
}

fn distance(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// Three nodes far apart ([`BodyExtent::far_apart`]); fewer where the body has fewer nodes.
fn far_apart_nodes(coords: &[[f64; 3]], centroid: &[f64; 3], dim: Dim) -> Vec<usize> {
    let farthest = |from: &dyn Fn(&[f64; 3]) -> f64| {
        (0..coords.len()).max_by(|&a, &b| from(&coords[a]).total_cmp(&from(&coords[b])))
    };
    let Some(a) = farthest(&|x| distance(x, centroid)) else {
        return Vec::new();
    };
    let Some(b) = farthest(&|x| distance(x, &coords[a])) else {
        return vec![a];
    };
    let mut nodes = vec![a, b];
    if dim == 3 {
        let (pa, pb) = (coords[a], coords[b]);
        let axis: [f64; 3] = std::array::from_fn(|k| pb[k] - pa[k]);
        let length = distance(&pa, &pb).max(f64::MIN_POSITIVE);
        let off_line = |x: &[f64; 3]| {
            let r: [f64; 3] = std::array::from_fn(|k| x[k] - pa[k]);
            let along = (0..3).map(|k| r[k] * axis[k]).sum::<f64>() / length;
            ((0..3).map(|k| r[k] * r[k]).sum::<f64>() - along * along).max(0.0)
        };
        nodes.extend(farthest(&off_line));
    }
    nodes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_grid_has_its_corners_far_apart_and_its_centre_at_the_middle() {
        // A 3 x 3 grid of the unit square, row by row.
        let coords: Vec<[f64; 3]> = (0..9)
            .map(|k| [0.5 * (k % 3) as f64, 0.5 * (k / 3) as f64, 0.0])
            .collect();
        let extent = BodyExtent::of(&coords, 2);
        assert_eq!((extent.low, extent.high), ([0.0; 3], [1.0, 1.0, 0.0]));
        assert_eq!(extent.centroid, [0.5, 0.5, 0.0]);
        assert!((extent.radius - 0.5f64.sqrt()).abs() < 1e-15);
        // The last of the equally far corners, then the corner opposite it.
        assert_eq!(extent.far_apart, [8, 0]);
    }
}
