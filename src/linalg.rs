//! Small dense linear systems, solved the one way the crate solves them.

/// Solves the N×N system `a · x = b` by Gauss–Jordan elimination with
/// partial pivoting; `None` when a pivot falls below `tiny` in magnitude.
pub(crate) fn solve<const N: usize>(
    mut a: [[f64; N]; N],
    mut b: [f64; N],
    tiny: f64,
) -> Option<[f64; N]> {
    for col in 0..N {
        let piv = (col..N).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < tiny {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for row in 0..N {
            if row != col {
                let f = a[row][col] / a[col][col];
                let prow = a[col];
                for (x, p) in a[row].iter_mut().zip(prow) {
                    *x -= f * p;
                }
                b[row] -= f * b[col];
            }
        }
    }
    Some(std::array::from_fn(|i| b[i] / a[i][i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_pivoting_system_and_refuses_a_singular_one() {
        // The first pivot is 0, so a row swap is needed.
        let a = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]];
        let x = solve(a, [7.0, 3.0, 6.0], 1e-300).unwrap();
        // x = (1, 2, 3) by hand: 0+4+3, 1+2+0, 3+0+3.
        for (got, want) in x.iter().zip([1.0, 2.0, 3.0]) {
            assert!((got - want).abs() < 1e-12, "{x:?}");
        }
        assert!(solve([[1.0, 2.0], [2.0, 4.0]], [1.0, 2.0], 1e-14).is_none());
    }
}
