//! SpookyHash V2 (Bob Jenkins), 128-bit, as Alembic uses it for the informational property and
//! object hashes at the end of every object-headers block. Incremental: `finish` leaves the state
//! alone, so a caller may keep updating after reading a hash (the object hash relies on that).
//! Words are little-endian; the public-domain algorithm is restated from its description.

const SC_CONST: u64 = 0xdead_beef_dead_beef;
const NUM_VARS: usize = 12;
const BLOCK_SIZE: usize = NUM_VARS * 8; // 96
const BUF_SIZE: usize = 2 * BLOCK_SIZE; // 192

/// A 128-bit hash as two words, written h1 then h2 (LE) wherever Alembic stores it.
pub type Hash128 = (u64, u64);

pub fn hash_bytes(h: Hash128) -> [u8; 16] {
    let mut out = [0u8; 16];
    out[..8].copy_from_slice(&h.0.to_le_bytes());
    out[8..].copy_from_slice(&h.1.to_le_bytes());
    out
}

/// One-shot hash with seeds (0, 0).
pub fn spooky128(data: &[u8]) -> Hash128 {
    let mut s = Spooky::new();
    s.update(data);
    s.finish()
}

/// Incremental SpookyHash V2 state.
#[derive(Clone)]
pub struct Spooky {
    data: [u8; BUF_SIZE],
    state: [u64; NUM_VARS],
    length: usize,
    remainder: usize,
}

impl Default for Spooky {
    fn default() -> Self {
        Spooky::new()
    }
}

impl Spooky {
    pub fn new() -> Self {
        Spooky { data: [0; BUF_SIZE], state: [0; NUM_VARS], length: 0, remainder: 0 }
    }

    pub fn update(&mut self, message: &[u8]) {
        let new_length = message.len() + self.remainder;
        if new_length < BUF_SIZE {
            self.data[self.remainder..new_length].copy_from_slice(message);
            self.length += message.len();
            self.remainder = new_length;
            return;
        }
        let mut h = if self.length < BUF_SIZE {
            let (a, b) = (self.state[0], self.state[1]);
            [a, b, SC_CONST, a, b, SC_CONST, a, b, SC_CONST, a, b, SC_CONST]
        } else {
            self.state
        };
        self.length += message.len();
        let mut rest = message;
        if self.remainder > 0 {
            let prefix = BUF_SIZE - self.remainder;
            self.data[self.remainder..].copy_from_slice(&rest[..prefix]);
            let buffer = self.data;
            mix(&words(&buffer[..BLOCK_SIZE]), &mut h);
            mix(&words(&buffer[BLOCK_SIZE..]), &mut h);
            rest = &rest[prefix..];
        }
        let mut blocks = rest.chunks_exact(BLOCK_SIZE);
        for block in &mut blocks {
            mix(&words(block), &mut h);
        }
        let tail = blocks.remainder();
        self.remainder = tail.len();
        self.data[..tail.len()].copy_from_slice(tail);
        self.state = h;
    }

    /// The hash of everything so far; the state is not changed.
    pub fn finish(&self) -> Hash128 {
        if self.length < BUF_SIZE {
            return short(&self.data[..self.length], self.state[0], self.state[1]);
        }
        let mut h = self.state;
        let mut buffer = self.data;
        let mut remainder = self.remainder;
        let mut start = 0;
        if remainder >= BLOCK_SIZE {
            mix(&words(&buffer[..BLOCK_SIZE]), &mut h);
            start = BLOCK_SIZE;
            remainder -= BLOCK_SIZE;
        }
        let last = &mut buffer[start..start + BLOCK_SIZE];
        last[remainder..].fill(0);
        last[BLOCK_SIZE - 1] = remainder as u8;
        end(&words(last), &mut h);
        (h[0], h[1])
    }
}

fn words(bytes: &[u8]) -> [u64; NUM_VARS] {
    std::array::from_fn(|i| u64::from_le_bytes(bytes[i * 8..i * 8 + 8].try_into().unwrap()))
}

fn le_partial(bytes: &[u8]) -> u64 {
    bytes.iter().rev().fold(0u64, |acc, &b| (acc << 8) | b as u64)
}

/// The hash of a message shorter than 192 bytes, seeded with (seed1, seed2).
fn short(message: &[u8], seed1: u64, seed2: u64) -> Hash128 {
    let length = message.len();
    let (mut a, mut b, mut c, mut d) = (seed1, seed2, SC_CONST, SC_CONST);
    let word = |bytes: &[u8], i: usize| u64::from_le_bytes(bytes[i * 8..i * 8 + 8].try_into().unwrap());
    let mut rest = message;
    if length > 15 {
        let mut chunks = rest.chunks_exact(32);
        for chunk in &mut chunks {
            c = c.wrapping_add(word(chunk, 0));
            d = d.wrapping_add(word(chunk, 1));
            short_mix(&mut a, &mut b, &mut c, &mut d);
            a = a.wrapping_add(word(chunk, 2));
            b = b.wrapping_add(word(chunk, 3));
        }
        rest = chunks.remainder();
        if rest.len() >= 16 {
            c = c.wrapping_add(word(rest, 0));
            d = d.wrapping_add(word(rest, 1));
            short_mix(&mut a, &mut b, &mut c, &mut d);
            rest = &rest[16..];
        }
    }
    d = d.wrapping_add((length as u64) << 56);
    if rest.is_empty() {
        c = c.wrapping_add(SC_CONST);
        d = d.wrapping_add(SC_CONST);
    } else {
        c = c.wrapping_add(le_partial(&rest[..rest.len().min(8)]));
        if rest.len() > 8 {
            d = d.wrapping_add(le_partial(&rest[8..]));
        }
    }
    short_end(&mut a, &mut b, &mut c, &mut d);
    (a, b)
}

fn short_mix(h0: &mut u64, h1: &mut u64, h2: &mut u64, h3: &mut u64) {
    *h2 = h2.rotate_left(50).wrapping_add(*h3);
    *h0 ^= *h2;
    *h3 = h3.rotate_left(52).wrapping_add(*h0);
    *h1 ^= *h3;
    *h0 = h0.rotate_left(30).wrapping_add(*h1);
    *h2 ^= *h0;
    *h1 = h1.rotate_left(41).wrapping_add(*h2);
    *h3 ^= *h1;
    *h2 = h2.rotate_left(54).wrapping_add(*h3);
    *h0 ^= *h2;
    *h3 = h3.rotate_left(48).wrapping_add(*h0);
    *h1 ^= *h3;
    *h0 = h0.rotate_left(38).wrapping_add(*h1);
    *h2 ^= *h0;
    *h1 = h1.rotate_left(37).wrapping_add(*h2);
    *h3 ^= *h1;
    *h2 = h2.rotate_left(62).wrapping_add(*h3);
    *h0 ^= *h2;
    *h3 = h3.rotate_left(34).wrapping_add(*h0);
    *h1 ^= *h3;
    *h0 = h0.rotate_left(5).wrapping_add(*h1);
    *h2 ^= *h0;
    *h1 = h1.rotate_left(36).wrapping_add(*h2);
    *h3 ^= *h1;
}

/// The four-word finalisation of the short hash. Alembic also uses it directly to chain sample
/// digests: `short_end_pair(chain, digest)` is the first two words after mixing.
fn short_end(h0: &mut u64, h1: &mut u64, h2: &mut u64, h3: &mut u64) {
    const STEPS: [u32; 11] = [15, 52, 26, 51, 28, 9, 47, 54, 32, 25, 63];
    // The words take turns: h3 ^= h2, h2 <<<= r, h3 += h2; then h0 from h3, h1 from h0, …
    let mut h = [*h0, *h1, *h2, *h3];
    for (i, r) in STEPS.into_iter().enumerate() {
        let target = (3 + i) % 4;
        let source = (2 + i) % 4;
        h[target] ^= h[source];
        h[source] = h[source].rotate_left(r);
        h[target] = h[target].wrapping_add(h[source]);
    }
    [*h0, *h1, *h2, *h3] = h;
}

/// Chains two 128-bit digests the way Alembic chains a property's sample keys.
pub fn chain_digests(chain: Hash128, digest: Hash128) -> Hash128 {
    let (mut a, mut b, mut c, mut d) = (chain.0, chain.1, digest.0, digest.1);
    short_end(&mut a, &mut b, &mut c, &mut d);
    (a, b)
}

fn mix(data: &[u64; NUM_VARS], s: &mut [u64; NUM_VARS]) {
    const ROT: [u32; NUM_VARS] = [11, 32, 43, 31, 17, 28, 39, 57, 55, 54, 22, 46];
    for i in 0..NUM_VARS {
        s[i] = s[i].wrapping_add(data[i]);
        s[(i + 2) % NUM_VARS] ^= s[(i + 10) % NUM_VARS];
        s[(i + 11) % NUM_VARS] ^= s[i];
        s[i] = s[i].rotate_left(ROT[i]);
        s[(i + 11) % NUM_VARS] = s[(i + 11) % NUM_VARS].wrapping_add(s[(i + 1) % NUM_VARS]);
    }
}

fn end_partial(h: &mut [u64; NUM_VARS]) {
    const ROT: [u32; NUM_VARS] = [44, 15, 34, 21, 38, 33, 10, 13, 38, 53, 42, 54];
    for i in 0..NUM_VARS {
        h[(i + 11) % NUM_VARS] = h[(i + 11) % NUM_VARS].wrapping_add(h[(i + 1) % NUM_VARS]);
        h[(i + 2) % NUM_VARS] ^= h[(i + 11) % NUM_VARS];
        h[(i + 1) % NUM_VARS] = h[(i + 1) % NUM_VARS].rotate_left(ROT[i]);
    }
}

fn end(data: &[u64; NUM_VARS], h: &mut [u64; NUM_VARS]) {
    for i in 0..NUM_VARS {
        h[i] = h[i].wrapping_add(data[i]);
    }
    end_partial(h);
    end_partial(h);
    end_partial(h);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hash_of_nothing_matches_the_note() {
        let expected =
            [0x19, 0x09, 0xf5, 0x6b, 0xfc, 0x06, 0x27, 0x23, 0xc7, 0x51, 0xe8, 0xb4, 0x65, 0xee, 0x72, 0x8b];
        assert_eq!(hash_bytes(spooky128(b"")), expected);
    }

    #[test]
    fn incremental_updates_match_one_shot_on_every_path() {
        // Lengths straddle the short (<192) and long paths and the 96-byte block edges.
        let data: Vec<u8> = (0..1000u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8).collect();
        for len in [0, 1, 15, 16, 31, 32, 95, 96, 191, 192, 193, 254, 287, 288, 500, 1000] {
            let whole = spooky128(&data[..len]);
            for split in [0, 1.min(len), len / 3, len / 2, len.saturating_sub(1)] {
                let mut s = Spooky::new();
                s.update(&data[..split]);
                let _ = s.finish(); // finishing must not disturb the state
                s.update(&data[split..len]);
                assert_eq!(s.finish(), whole, "len {len} split {split}");
            }
        }
    }

    #[test]
    fn matches_the_reference_implementation_on_short_and_long_inputs() {
        // Bob Jenkins' SpookyV2.cpp (from the `spooky` 2.0.0 sdist, compiled as an oracle),
        // Hash128 with seeds (0, 0) over byte i = (i · 2654435761 mod 2³²) >> 13.
        let data: Vec<u8> = (0..1000u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8).collect();
        let vectors: [(usize, u64, u64); 8] = [
            (0, 0x232706fc6bf50919, 0x8b72ee65b4e851c7),
            (5, 0xefa9bc3cae899590, 0xa5e8e1db3252147f),
            (31, 0xded4a87eb6f2a081, 0x4b5e41136c2d89e8),
            (191, 0x198ef0301af3c6df, 0xf5c090f4975f236a),
            (192, 0x7eff6199f98a6197, 0x8edfb4a97aea8983),
            (254, 0x128ca0368c09835d, 0x9ffc4420fa1967e9),
            (300, 0xe22b706d55d8ec43, 0x3b360dc0c60a71d5),
            (1000, 0x011b9d3d431e7839, 0x42f5df0dbfe5f241),
        ];
        for (len, h1, h2) in vectors {
            assert_eq!(spooky128(&data[..len]), (h1, h2), "length {len}");
        }
    }

    #[test]
    fn long_inputs_differ_from_short_prefixes() {
        let data = vec![7u8; 400];
        assert_ne!(spooky128(&data[..191]), spooky128(&data[..192]));
        assert_ne!(spooky128(&data[..300]), spooky128(&data[..301]));
    }
}
