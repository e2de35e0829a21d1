//! Deterministic pseudo-random matrices for tests: a seed gives the same entries on every
//! machine. Two generators, each drawing a double in `[-0.5, 0.5)` from the top 53 bits of its
//! state: Knuth's 64-bit linear congruential generator (MMIX, [`Lcg`]) and Marsaglia's xorshift64
//! ([`XorShift`]). Not for statistics: for reproducible test data.

use nalgebra::DMatrix;

/// Knuth's MMIX linear congruential generator; the state advances before each draw.
#[derive(Debug, Clone)]
pub struct Lcg(pub u64);

impl Lcg {
    /// The next state.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0
    }

    /// A number in `[-0.5, 0.5)` from the top 53 bits of the next state.
    pub fn centred(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }
}

/// Marsaglia's xorshift64 generator (shifts 13, 7, 17); the state advances before each draw and
/// must not start at 0.
#[derive(Debug, Clone)]
pub struct XorShift(pub u64);

impl XorShift {
    /// A number in `[-0.5, 0.5)` from the top 53 bits of the next state.
    pub fn centred(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// A `rows × cols` matrix of [`Lcg::centred`] draws from `seed`, filled column by column.
#[must_use]
pub fn centred_matrix(rows: usize, cols: usize, seed: u64) -> DMatrix<f64> {
    let mut g = Lcg(seed);
    DMatrix::from_fn(rows, cols, |_, _| g.centred())
}

/// A symmetric positive definite `n × n` matrix `H Hᵀ + shift · I` with `H` the
/// [`centred_matrix`] of `seed` (`shift > 0` bounds its smallest eigenvalue from below).
#[must_use]
pub fn spd_matrix(n: usize, seed: u64, shift: f64) -> DMatrix<f64> {
    let h = centred_matrix(n, n, seed);
    &h * h.transpose() + DMatrix::identity(n, n) * shift
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The draws the tests of the workspace were written against: the generator's first states
    /// from seed 1, by hand.
    #[test]
    fn draws_follow_the_mmix_recurrence() {
        let mut g = Lcg(1);
        let s1 = 6364136223846793005u64.wrapping_add(1442695040888963407);
        assert_eq!(g.next_u64(), s1);
        let s2 = s1.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let expected = ((s2 >> 11) as f64 / 9007199254740992.0) - 0.5;
        assert_eq!(g.centred().to_bits(), expected.to_bits());
        let m = centred_matrix(2, 3, 7);
        let mut g = Lcg(7);
        for j in 0..3 {
            for i in 0..2 {
                assert_eq!(m[(i, j)].to_bits(), g.centred().to_bits());
            }
        }
        let mut x = XorShift(1);
        let s = 1u64 ^ (1 << 13);
        let s = s ^ (s >> 7);
        let s = s ^ (s << 17);
        assert_eq!(x.centred().to_bits(), ((s >> 11) as f64 / 9007199254740992.0 - 0.5).to_bits());
        let p = spd_matrix(3, 5, 0.1);
        assert!((&p - p.transpose()).amax() == 0.0);
        assert!(p.clone().cholesky().is_some());
    }
}
