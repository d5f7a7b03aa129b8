//! Per-pixel sample generation. Every pixel seeds its own stream from its coordinates and the
//! render seed, so an image is bit-identical whatever the thread count or tile order.
//!
//! The default sampler is a padded, Owen-scrambled Sobol (0,2)-sequence: each pair of dimensions
//! (pixel position, BSDF lobe, light sample…) draws from the first two Sobol dimensions, with the
//! sample order shuffled and the digits scrambled by per-pixel, per-dimension hashes (Burley 2020,
//! "Practical hash-based Owen scrambling"). Stratified in every 2D projection, it converges faster
//! than independent random numbers; `Independent` exists to measure that gain.

/// Which sample sequence drives the integrator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    #[default]
    Sobol,
    Independent,
}

/// A 64-bit mix (SplitMix64's finaliser): decorrelates nearby seeds.
#[inline]
pub fn mix64(mut x: u64) -> u64 {
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Hash of a few words, for seeding.
#[inline]
pub fn hash(words: &[u64]) -> u64 {
    words.iter().fold(0x9e37_79b9_7f4a_7c15, |h, &w| mix64(h ^ w.wrapping_add(0x9e37_79b9_7f4a_7c15)))
}

/// A float in [0, 1) from the top 24 bits of a 32-bit value.
#[inline]
fn unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Second Sobol dimension (the first is the bit-reversed index).
#[inline]
fn sobol_dim1(mut index: u32) -> u32 {
    let mut result = 0u32;
    let mut v = 1u32 << 31;
    while index != 0 {
        if index & 1 != 0 {
            result ^= v;
        }
        index >>= 1;
        v ^= v >> 1;
    }
    result
}

/// Nested uniform (Owen) scrambling of a 32-bit fixed-point value, by a hash on reversed bits.
#[inline]
fn owen_scramble(value: u32, seed: u32) -> u32 {
    let mut x = value.reverse_bits();
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x.reverse_bits()
}

/// A random permutation of `0..n` evaluated at `i` (Kensler 2013, cycle-walking hash).
fn permute(mut i: u32, n: u32, seed: u32) -> u32 {
    if n <= 1 {
        return 0;
    }
    let mut w = n - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= seed;
        i = i.wrapping_mul(0xe170_893d);
        i ^= seed >> 16;
        i ^= (i & w) >> 4;
        i ^= seed >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= seed >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | seed >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < n {
            return i.wrapping_add(seed) % n;
        }
    }
}

/// The sample stream of one pixel sample: call [`Sampler::get_1d`] / [`Sampler::get_2d`] in a
/// fixed order; each call consumes one dimension pair.
pub struct Sampler {
    kind: SamplerKind,
    pixel_seed: u64,
    index: u32,
    count: u32,
    dimension: u32,
    rng: u64,
}

impl Sampler {
    /// The stream for sample `index` of `count` in the pixel whose seed is `pixel_seed`.
    pub fn new(kind: SamplerKind, pixel_seed: u64, index: u32, count: u32) -> Sampler {
        Sampler { kind, pixel_seed, index, count, dimension: 0, rng: hash(&[pixel_seed, index as u64]) }
    }

    pub fn get_2d(&mut self) -> [f32; 2] {
        let dimension = self.dimension;
        self.dimension += 1;
        match self.kind {
            SamplerKind::Independent => [self.next_random(), self.next_random()],
            SamplerKind::Sobol => {
                let h = hash(&[self.pixel_seed, dimension as u64]);
                let shuffled = permute(self.index, self.count, h as u32);
                let x = owen_scramble(shuffled.reverse_bits(), (h >> 32) as u32);
                let y = owen_scramble(sobol_dim1(shuffled), mix64(h) as u32);
                [unit(x), unit(y)]
            }
        }
    }

    pub fn get_1d(&mut self) -> f32 {
        self.get_2d()[0]
    }

    fn next_random(&mut self) -> f32 {
        self.rng = mix64(self.rng.wrapping_add(0x9e37_79b9_7f4a_7c15));
        unit((self.rng >> 32) as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_is_a_bijection() {
        for n in [1u32, 7, 16, 64, 100] {
            let mut seen: Vec<u32> = (0..n).map(|i| permute(i, n, 0xdead_beef)).collect();
            seen.sort();
            assert_eq!(seen, (0..n).collect::<Vec<_>>(), "n = {n}");
        }
    }

    /// A (0,2)-sequence: 16 points put exactly one point in each cell of every 2^a × 2^b grid
    /// with a + b = 4, and scrambling keeps that.
    #[test]
    fn sobol_pairs_are_stratified_in_every_elementary_interval() {
        let points: Vec<[f32; 2]> =
            (0..16).map(|i| Sampler::new(SamplerKind::Sobol, 42, i, 16).get_2d()).collect();
        for a in 0..=4u32 {
            let (nx, ny) = (1usize << a, 1usize << (4 - a));
            let mut cells = vec![0; 16];
            for p in &points {
                let cx = (p[0] * nx as f32) as usize;
                let cy = (p[1] * ny as f32) as usize;
                cells[cy * nx + cx] += 1;
            }
            assert!(cells.iter().all(|&c| c == 1), "grid {nx}x{ny}: {cells:?}");
        }
    }

    #[test]
    fn streams_depend_on_pixel_and_dimension() {
        let a = Sampler::new(SamplerKind::Sobol, 1, 0, 16).get_2d();
        let b = Sampler::new(SamplerKind::Sobol, 2, 0, 16).get_2d();
        assert_ne!(a, b);
        let mut s = Sampler::new(SamplerKind::Sobol, 1, 0, 16);
        assert_ne!(s.get_2d(), s.get_2d());
    }
}
