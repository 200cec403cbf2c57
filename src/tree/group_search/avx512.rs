//! The gathered block's two inner loops for `f32` rows on processors with AVX-512 (F and VL):
//! a member's keys within a bound, sixteen points per step with the hits compressed into place
//! instead of taken one bit at a time, and the ranks of up to [`super::gather`]'s `RANK_MAX`
//! keys, eight compares per instruction. Both give exactly what their portable forms give (the
//! same squared distances, bit for bit, summed in the same order; the same keys in the same
//! order); `gather.rs` calls them only where the processor has the instructions.

use super::BLOCK as LANES;
use std::arch::x86_64::*;

// One step is one register of sixteen `f32` lanes, the block's padding.
const _: () = assert!(LANES == 16);

/// Writes into `keys` the packed keys (`order::key32`: the squared distance's bits above the
/// index) of the block's points within `bound` of `q`, other than `self_id`, in block order;
/// returns how many. `coords[j]` holds the block's coordinates in dimension `j`, padded to a
/// multiple of sixteen; `ids` their indices. `keys` needs eight slots more than `ids` has
/// entries (each step stores eight whole keys at a time).
///
/// # Safety
/// The processor must support AVX-512 F and VL.
#[target_feature(enable = "avx512f,avx512vl")]
pub(super) unsafe fn keys_within<const D: usize>(
    coords: &[Vec<f32>; D],
    ids: &[u32],
    q: &[f32; D],
    self_id: u32,
    bound: f32,
    keys: &mut [u64],
) -> usize {
    let count = ids.len();
    let padded = count.div_ceil(LANES) * LANES;
    assert!(coords.iter().all(|c| c.len() >= padded) && keys.len() >= count + 8);
    let (bound, own) = (_mm512_set1_ps(bound), _mm512_set1_epi32(self_id as i32));
    let mut n = 0;
    for start in (0..count).step_by(LANES) {
        // `0 + t0²`, then `+ t1²` and so on: the portable sum's order and bits (no fused ops)
        let mut d = _mm512_setzero_ps();
        for (c, &qj) in coords.iter().zip(q) {
            // SAFETY: `start + 16 ≤ padded ≤ c.len()` (asserted above).
            let x = unsafe { _mm512_loadu_ps(c.as_ptr().add(start)) };
            let t = _mm512_sub_ps(_mm512_set1_ps(qj), x);
            d = _mm512_add_ps(d, _mm512_mul_ps(t, t));
        }
        let valid: __mmask16 = if count - start < LANES {
            (1u16 << (count - start)) - 1
        } else {
            u16::MAX
        };
        // SAFETY: the masked load reads only the `valid` lanes, `start..count`, inside `ids`.
        let id = unsafe { _mm512_maskz_loadu_epi32(valid, ids.as_ptr().add(start).cast()) };
        let hits = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(valid, d, bound)
            & _mm512_mask_cmpneq_epi32_mask(valid, id, own);
        let bits = _mm512_castps_si512(d);
        let halves = [
            (
                _mm512_castsi512_si256(bits),
                _mm512_castsi512_si256(id),
                hits as u8,
            ),
            (
                _mm512_extracti64x4_epi64::<1>(bits),
                _mm512_extracti64x4_epi64::<1>(id),
                (hits >> 8) as u8,
            ),
        ];
        for (dist_bits, index, take) in halves {
            let key = _mm512_or_si512(
                _mm512_slli_epi64::<32>(_mm512_cvtepu32_epi64(dist_bits)),
                _mm512_cvtepu32_epi64(index),
            );
            // compressed in a register and stored whole (a compressing store to memory is
            // slow on some processors): the lanes past the hits are overwritten next
            let packed = _mm512_maskz_compress_epi64(take, key);
            // SAFETY: `n ≤ count` (each valid lane so far gave at most one key), so the
            // eight slots from `n` lie inside `keys` (`count + 8` slots, asserted above).
            unsafe { _mm512_storeu_si512(keys.as_mut_ptr().add(n).cast(), packed) };
            n += take.count_ones() as usize;
        }
    }
    n
}

/// `below[i]` = how many of the distinct `keys` are less than `keys[i]`, for eight keys at a
/// time in the lanes of a register: each key is compared with all eight at once and adds one
/// to the lanes it is below.
///
/// # Safety
/// The processor must support AVX-512 F and VL.
#[target_feature(enable = "avx512f,avx512vl")]
pub(super) unsafe fn count_below(keys: &[u64], below: &mut [u32]) {
    let n = keys.len().min(below.len());
    let one = _mm512_set1_epi64(1);
    for start in (0..n).step_by(8) {
        let mask = ((1u32 << (n - start).min(8)) - 1) as __mmask8;
        // SAFETY: the masked load reads only the keys `start..min(start + 8, n)`, inside
        // `keys`; the other lanes are zero.
        let a = unsafe { _mm512_maskz_loadu_epi64(mask, keys.as_ptr().add(start).cast()) };
        let mut count = _mm512_setzero_si512();
        for &b in &keys[..n] {
            let above = _mm512_cmpgt_epu64_mask(a, _mm512_set1_epi64(b as i64));
            count = _mm512_mask_add_epi64(count, above, count, one);
        }
        // SAFETY: the masked store writes only the counts `start..min(start + 8, n)`, inside
        // `below`.
        unsafe {
            _mm512_mask_cvtepi64_storeu_epi32(below.as_mut_ptr().add(start).cast(), mask, count)
        };
    }
}
