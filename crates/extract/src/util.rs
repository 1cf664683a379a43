//! Leaf helpers shared by the passes: bit-set iteration and reads, and the sizing of buffers
//! that a pass then overwrites. Imports nothing of the crate, so any module may use it.

use rayon::prelude::*;

/// Calls `visit(n)` for each set bit `n < len` of the bit set `words` counted from bit `start`.
#[inline(always)]
pub(crate) fn for_each_bit(words: &[u64], start: usize, len: usize, mut visit: impl FnMut(usize)) {
    let mut n = 0;
    while n < len {
        let take = (len - n).min(64);
        let mut bits = bits_at(words, start + n);
        if take < 64 {
            bits &= (1u64 << take) - 1;
        }
        while bits != 0 {
            visit(n + bits.trailing_zeros() as usize);
            bits &= bits - 1;
        }
        n += take;
    }
}

/// The 64 bits of `words` starting at bit `pos` (bit k = slot `pos + k`); `words` has one word
/// of padding past the last slot.
#[inline(always)]
pub(crate) fn bits_at(words: &[u64], pos: usize) -> u64 {
    let (w, s) = (pos >> 6, pos & 63);
    let lo = words[w] >> s;
    if s == 0 {
        lo
    } else {
        lo | (words[w + 1] << (64 - s))
    }
}

/// Bit k set where `values[k] < iso` (at most 64 values). A full word is built a byte at a time,
/// which the compiler turns into wide comparisons (about 40% faster than bit by bit).
#[inline(always)]
pub(crate) fn inside_word(values: &[f32], iso: f32) -> u64 {
    match <&[f32; 64]>::try_from(values) {
        Ok(v) => {
            let mut bytes = [0u8; 8];
            for (b, c) in bytes.iter_mut().zip(v.as_chunks::<8>().0) {
                *b = c
                    .iter()
                    .enumerate()
                    .fold(0u8, |b, (k, &f)| b | (u8::from(f < iso) << k));
            }
            u64::from_le_bytes(bytes)
        }
        Err(_) => values
            .iter()
            .enumerate()
            .fold(0u64, |x, (k, &f)| x | (u64::from(f < iso) << k)),
    }
}

/// [`inside_word`] of 64 values and whether any of them is not finite, from one read of the
/// values: four at a time on x86-64 (an ordered less-than, NaN outside as with `<`), and
/// `v - v`, which is 0 for a finite `v` and NaN for NaN and infinities, summed per lane (a sum
/// that meets a NaN stays NaN). What the first pass over a caller's values uses to refuse
/// non-finite ones without a pass of its own.
#[inline(always)]
pub(crate) fn inside_word_finite64(values: &[f32; 64], iso: f32) -> (u64, bool) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{
            _mm_add_ps, _mm_cmplt_ps, _mm_cmpunord_ps, _mm_loadu_ps, _mm_movemask_ps, _mm_set1_ps,
            _mm_setzero_ps, _mm_sub_ps,
        };
        let mut word = 0u64;
        // SAFETY: SSE2 is in the x86-64 baseline; each load reads the 4 values of its chunk
        // (unaligned).
        unsafe {
            let t = _mm_set1_ps(iso);
            let mut acc = _mm_setzero_ps();
            for (i, four) in values.as_chunks::<4>().0.iter().enumerate() {
                let v = _mm_loadu_ps(four.as_ptr());
                let mask = _mm_movemask_ps(_mm_cmplt_ps(v, t)) as u64;
                word |= mask << (4 * i);
                acc = _mm_add_ps(acc, _mm_sub_ps(v, v));
            }
            (word, _mm_movemask_ps(_mm_cmpunord_ps(acc, acc)) != 0)
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        (
            inside_word(values, iso),
            values.iter().any(|v| !v.is_finite()),
        )
    }
}

/// [`inside_word`] of at most 64 values and whether any of them is not finite
/// ([`inside_word_finite64`] for a full word).
#[inline(always)]
pub(crate) fn inside_word_finite(values: &[f32], iso: f32) -> (u64, bool) {
    match <&[f32; 64]>::try_from(values) {
        Ok(v) => inside_word_finite64(v, iso),
        Err(_) => (
            inside_word(values, iso),
            values.iter().any(|v| !v.is_finite()),
        ),
    }
}

/// Whether `values` holds a NaN or an infinity: branch-free, at memory speed (`v - v` summed
/// in 32 independent lanes, which the compiler keeps in vector registers; see
/// [`inside_word_finite64`]). For a pass that reads no value of its own before a library does.
pub(crate) fn any_non_finite(values: &[f32]) -> bool {
    const LANES: usize = 32;
    let mut acc = [0f32; LANES];
    let chunks = values.chunks_exact(LANES);
    let rest = chunks.remainder();
    for c in chunks {
        for (a, v) in acc.iter_mut().zip(c) {
            // Not 0: NaN for a non-finite v (the point of the check).
            #[allow(clippy::eq_op)]
            {
                *a += v - v;
            }
        }
    }
    acc.iter().any(|a| *a != 0.0) || rest.iter().any(|v| !v.is_finite())
}

/// [`bits_at`] from any position, before or past `words` too: bits outside `words` read as 0.
#[inline]
pub(crate) fn bits_at_signed(words: &[u64], pos: isize) -> u64 {
    let (w, s) = (pos.div_euclid(64), pos.rem_euclid(64) as u32);
    let word = |i: isize| {
        usize::try_from(i)
            .ok()
            .and_then(|i| words.get(i))
            .copied()
            .unwrap_or(0)
    };
    let lo = word(w) >> s;
    if s == 0 {
        lo
    } else {
        lo | (word(w + 1) << (64 - s))
    }
}

/// Sets `v` to length `n` for a pass that then writes every element: elements kept from an
/// earlier extraction are not cleared (a reused buffer costs no memset), new ones are zeroed in
/// parallel (first touches of fresh memory included).
pub(crate) fn overwritten<T: Copy + Send + Sync>(
    v: &mut Vec<T>,
    n: usize,
    zero: T,
    pool: &rayon::ThreadPool,
) {
    v.truncate(n);
    let more = n - v.len();
    if more > 0 {
        pool.install(|| v.par_extend(rayon::iter::repeat_n(zero, more)));
    }
}

/// Sets `v` to `n` copies of `value`, written in parallel (a table every entry of which a pass
/// reads before writing it).
pub(crate) fn filled<T: Copy + Send + Sync>(
    v: &mut Vec<T>,
    n: usize,
    value: T,
    pool: &rayon::ThreadPool,
) {
    v.clear();
    pool.install(|| v.par_extend(rayon::iter::repeat_n(value, n)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finite_checks_see_every_position_and_kind() {
        // Every position of a word, full (64) and partial (45), and of a length with a
        // remainder after the 32 lanes; large finite values (whose v - v is 0) are not
        // flagged, and the inside bits are those of `inside_word`.
        let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -f32::NAN];
        for len in [64, 45, 103] {
            let mut v: Vec<f32> = (0..len).map(|i| (i as f32 - 30.0) * 1e36).collect();
            v[7] = f32::MAX;
            v[8] = f32::MIN;
            v[9] = f32::MIN_POSITIVE / 4.0;
            v[10] = -0.0;
            assert!(!any_non_finite(&v));
            if len <= 64 {
                assert_eq!(inside_word_finite(&v, 0.0), (inside_word(&v, 0.0), false));
            }
            for at in 0..len {
                for b in bad {
                    let keep = v[at];
                    v[at] = b;
                    assert!(any_non_finite(&v), "{b} at {at} of {len}");
                    if len <= 64 {
                        assert_eq!(
                            inside_word_finite(&v, 1e30),
                            (inside_word(&v, 1e30), true),
                            "{b} at {at} of {len}"
                        );
                    }
                    v[at] = keep;
                }
            }
        }
        assert!(!any_non_finite(&[]));
    }

    #[test]
    fn for_each_bit_visits_exactly_the_set_bits_from_any_start() {
        let mut words = vec![0u64; 6];
        let set: Vec<usize> = (0..320).filter(|i| (i * 7 + i / 3) % 5 == 0).collect();
        for &i in &set {
            words[i >> 6] |= 1 << (i & 63);
        }
        for start in [0, 1, 13, 63, 64, 65, 200] {
            for len in [0, 1, 5, 63, 64, 65, 100, 320 - start] {
                if start + len > 320 {
                    continue;
                }
                let mut seen = Vec::new();
                for_each_bit(&words, start, len, |n| seen.push(start + n));
                let want: Vec<usize> = set
                    .iter()
                    .copied()
                    .filter(|&i| i >= start && i < start + len)
                    .collect();
                assert_eq!(seen, want, "start {start} len {len}");
            }
        }
    }
}
