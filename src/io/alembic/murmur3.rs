//! MurmurHash3 x64 128-bit (Austin Appleby), seed 0: the 16-byte key Alembic stores in front of
//! every sample and uses to de-duplicate identical samples across the archive.

const C1: u64 = 0x87c3_7b91_1142_53d5;
const C2: u64 = 0x4cf5_ad43_2745_937f;

/// The (h1, h2) pair of MurmurHash3_x64_128 over `data` with seed 0.
pub fn murmur3_x64_128(data: &[u8]) -> (u64, u64) {
    let (mut h1, mut h2) = (0u64, 0u64);
    let mut blocks = data.chunks_exact(16);
    for block in &mut blocks {
        let k1 = u64::from_le_bytes(block[..8].try_into().unwrap());
        let k2 = u64::from_le_bytes(block[8..].try_into().unwrap());
        h1 ^= mix_k1(k1);
        h1 = h1.rotate_left(27).wrapping_add(h2).wrapping_mul(5).wrapping_add(0x52dc_e729);
        h2 ^= mix_k2(k2);
        h2 = h2.rotate_left(31).wrapping_add(h1).wrapping_mul(5).wrapping_add(0x3849_5ab5);
    }
    let tail = blocks.remainder();
    if tail.len() > 8 {
        h2 ^= mix_k2(le_partial(&tail[8..]));
    }
    if !tail.is_empty() {
        h1 ^= mix_k1(le_partial(&tail[..tail.len().min(8)]));
    }
    let len = data.len() as u64;
    h1 ^= len;
    h2 ^= len;
    h1 = h1.wrapping_add(h2);
    h2 = h2.wrapping_add(h1);
    h1 = fmix64(h1);
    h2 = fmix64(h2);
    h1 = h1.wrapping_add(h2);
    h2 = h2.wrapping_add(h1);
    (h1, h2)
}

/// The 16 key bytes as Alembic writes them: h1 then h2, each little-endian.
pub fn sample_key(data: &[u8]) -> [u8; 16] {
    let (h1, h2) = murmur3_x64_128(data);
    let mut key = [0u8; 16];
    key[..8].copy_from_slice(&h1.to_le_bytes());
    key[8..].copy_from_slice(&h2.to_le_bytes());
    key
}

fn mix_k1(k: u64) -> u64 {
    k.wrapping_mul(C1).rotate_left(31).wrapping_mul(C2)
}

fn mix_k2(k: u64) -> u64 {
    k.wrapping_mul(C2).rotate_left(33).wrapping_mul(C1)
}

fn le_partial(bytes: &[u8]) -> u64 {
    bytes.iter().rev().fold(0u64, |acc, &b| (acc << 8) | b as u64)
}

fn fmix64(mut k: u64) -> u64 {
    k ^= k >> 33;
    k = k.wrapping_mul(0xff51_afd7_ed55_8ccd);
    k ^= k >> 33;
    k = k.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    k ^ (k >> 33)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_input_hashes_to_zero() {
        assert_eq!(murmur3_x64_128(b""), (0, 0));
    }

    #[test]
    fn hello_matches_the_reference_vector() {
        assert_eq!(murmur3_x64_128(b"hello"), (0xcbd8_a7b3_41bd_9b02, 0x5b1e_906a_48ae_1d19));
    }

    #[test]
    fn worked_example_positions_key() {
        // The P sample of the note's worked example: 18 f32.
        let p: [f32; 18] = [0., 0., 0., 0., 1., 0., 0., 2., 0., 1., 0., 0., 1., 1., 0., 1., 2., 0.];
        let bytes: Vec<u8> = p.iter().flat_map(|v| v.to_le_bytes()).collect();
        let expected =
            [0x20, 0x37, 0x58, 0x42, 0x22, 0x06, 0x0a, 0x5c, 0x94, 0xee, 0x01, 0x3b, 0x1b, 0xc1, 0x97, 0x99];
        assert_eq!(sample_key(&bytes), expected);
    }
}
