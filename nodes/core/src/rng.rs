//! The Mersenne Twister (MT19937) and the few draws the reference benchmark makes with it.
//!
//! The reference uses two generators, both MT19937 but seeded and consumed differently:
//!
//! * CPython's `random` module shuffles the task list of `sample_tasks`
//!   (docs/src/reference-facts.md §7.2):
//!   [`Mt19937::python_seed`], [`Mt19937::getrandbits`], [`Mt19937::randbelow`],
//!   [`Mt19937::shuffle`].
//! * numpy's legacy global generator (`np.random`) places the object at each reset
//!   (docs/src/reference-facts.md §7.3): [`Mt19937::numpy_seed`], [`Mt19937::random_sample`],
//!   [`Mt19937::uniform`], [`Mt19937::standard_normal`].
//!
//! Every function follows its reference step by step, because the point is bit-exact
//! reproduction: the same seed must give the same task split and the same object placement as
//! the reference, not merely draws from the same distribution. The generator itself is written
//! from the algorithm of Matsumoto and Nishimura (their reference `init_genrand`,
//! `init_by_array` and `genrand_int32`).

use std::fmt;

/// Degree of recurrence: the state is this many 32-bit words.
const N: usize = 624;
/// Middle word offset of the recurrence.
const M: usize = 397;
/// The twist matrix's last row.
const MATRIX_A: u32 = 0x9908_b0df;
/// The most significant bit of a word.
const UPPER_MASK: u32 = 0x8000_0000;
/// The 31 least significant bits of a word.
const LOWER_MASK: u32 = 0x7fff_ffff;

/// Words of state (numpy's `get_state()` key length).
pub const MT_STATE_WORDS: usize = N;

/// A 32-bit Mersenne Twister with the draws of CPython's `random` and numpy's legacy
/// `np.random`, bit-identical to both.
///
/// The CPython-style draws ([`getrandbits`](Self::getrandbits), [`randbelow`](Self::randbelow),
/// [`shuffle`](Self::shuffle)) and the numpy-style draws ([`random_sample`](Self::random_sample),
/// [`uniform`](Self::uniform), [`standard_normal`](Self::standard_normal)) all consume the same
/// stream of 32-bit outputs; each family matches its reference when the generator is seeded the
/// way that reference seeds ([`python_seed`](Self::python_seed) or
/// [`numpy_seed`](Self::numpy_seed)).
#[derive(Clone, PartialEq)]
pub struct Mt19937 {
    state: [u32; N],
    /// Next word of `state` to temper; `N` means the state must be regenerated first.
    index: usize,
    /// numpy's cached second normal from the last polar Box–Muller pair.
    gauss: Option<f64>,
}

impl fmt::Debug for Mt19937 {
    /// The 624 state words are noise in a debug print; show the position and the cache.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Mt19937")
            .field("index", &self.index)
            .field("gauss", &self.gauss)
            .finish_non_exhaustive()
    }
}

impl Mt19937 {
    /// The reference `init_genrand(s)`: fill the state from one 32-bit seed with Knuth's
    /// multiplier 1812433253.
    pub fn init_genrand(seed: u32) -> Self {
        let mut state = [0u32; N];
        state[0] = seed;
        for i in 1..N {
            let prev = state[i - 1];
            state[i] = 1_812_433_253u32
                .wrapping_mul(prev ^ (prev >> 30))
                .wrapping_add(i as u32);
        }
        Mt19937 {
            state,
            index: N,
            gauss: None,
        }
    }

    /// The reference `init_by_array(key)`: `init_genrand(19650218)`, then mix every key word
    /// into the state (at least `N` rounds, so short keys still touch every word), then force
    /// the top bit of word 0 so the state is never all zero.
    ///
    /// An empty key is treated as `[0]`, which is what CPython passes for seed 0.
    pub fn init_by_array(key: &[u32]) -> Self {
        let key: &[u32] = if key.is_empty() { &[0] } else { key };
        let mut mt = Self::init_genrand(19_650_218);
        let s = &mut mt.state;
        let mut i = 1;
        let mut j = 0;
        for _ in 0..N.max(key.len()) {
            let prev = s[i - 1];
            s[i] = (s[i] ^ (prev ^ (prev >> 30)).wrapping_mul(1_664_525))
                .wrapping_add(key[j])
                .wrapping_add(j as u32);
            i += 1;
            j += 1;
            if i >= N {
                s[0] = s[N - 1];
                i = 1;
            }
            if j >= key.len() {
                j = 0;
            }
        }
        for _ in 0..N - 1 {
            let prev = s[i - 1];
            s[i] =
                (s[i] ^ (prev ^ (prev >> 30)).wrapping_mul(1_566_083_941)).wrapping_sub(i as u32);
            i += 1;
            if i >= N {
                s[0] = s[N - 1];
                i = 1;
            }
        }
        s[0] = UPPER_MASK;
        mt
    }

    /// Seeded as CPython's `random.seed(n)` seeds for a non-negative int `n`:
    /// `init_by_array` over the 32-bit little-endian words of `n`, least significant first,
    /// with no leading zero words (`[0]` for `n = 0`).
    ///
    /// This is what the reference's `sample_tasks(shuffling_seed=n)` does, so the word split
    /// must match exactly: `n < 2³²` is a one-word key, larger `n` a two-word key, and the two
    /// give unrelated streams. (CPython uses `|n|` for negative ints; callers of this suite
    /// only have non-negative seeds.)
    pub fn python_seed(n: u64) -> Self {
        let low = n as u32;
        let high = (n >> 32) as u32;
        if high == 0 {
            Self::init_by_array(&[low])
        } else {
            Self::init_by_array(&[low, high])
        }
    }

    /// Seeded as numpy's legacy `np.random.seed(n)` seeds for an int `n`: plain
    /// `init_genrand(n)`, *not* `init_by_array` — the same integer seeds CPython and numpy into
    /// different streams. Also clears the cached normal, as numpy's seeding does.
    pub fn numpy_seed(n: u32) -> Self {
        Self::init_genrand(n)
    }

    /// The generator in the state numpy's legacy `np.random.get_state()` describes:
    /// `('MT19937', key, pos, has_gauss, cached_gaussian)` — the 624 words, the position of
    /// the next word (624: regenerate first) and the cached normal, if any. `None` when `pos`
    /// is past 624.
    pub fn from_numpy_state(key: [u32; N], pos: usize, gauss: Option<f64>) -> Option<Self> {
        (pos <= N).then_some(Mt19937 {
            state: key,
            index: pos,
            gauss,
        })
    }

    /// The state as numpy's `np.random.set_state()` takes it: (key, pos, cached normal).
    pub fn numpy_state(&self) -> ([u32; N], usize, Option<f64>) {
        (self.state, self.index, self.gauss)
    }

    /// The reference `genrand_int32`: the next tempered 32-bit output, regenerating all `N`
    /// words at once when they are used up.
    pub fn next_u32(&mut self) -> u32 {
        if self.index >= N {
            self.twist();
        }
        let mut y = self.state[self.index];
        self.index += 1;
        y ^= y >> 11;
        y ^= (y << 7) & 0x9d2c_5680;
        y ^= (y << 15) & 0xefc6_0000;
        y ^= y >> 18;
        y
    }

    /// Regenerate the whole state from the recurrence (the first half of `genrand_int32`).
    fn twist(&mut self) {
        let s = &mut self.state;
        for k in 0..N {
            let y = (s[k] & UPPER_MASK) | (s[(k + 1) % N] & LOWER_MASK);
            let mag = if y & 1 == 1 { MATRIX_A } else { 0 };
            s[k] = s[(k + M) % N] ^ (y >> 1) ^ mag;
        }
        self.index = 0;
    }

    /// CPython's `random.getrandbits(k)` for `k <= 32`: the top `k` bits of one output (the
    /// high bits, not the low ones, which is what makes `randbelow` agree with CPython).
    /// `k = 0` returns 0 without consuming an output, as CPython 3.9+ does.
    ///
    /// # Panics
    /// If `k > 32` (CPython would combine several outputs; nothing here needs that).
    pub fn getrandbits(&mut self, k: u32) -> u32 {
        assert!(k <= 32, "getrandbits supports k <= 32, got {k}");
        if k == 0 {
            return 0;
        }
        self.next_u32() >> (32 - k)
    }

    /// CPython's `Random._randbelow(n)` (what `randrange(n)` and `shuffle` use): draw
    /// `getrandbits(bit_length(n))` until it is below `n`. Rejection rather than a modulo is
    /// what keeps the count of consumed outputs — and so every later draw — identical.
    ///
    /// # Panics
    /// If `n == 0` (CPython would loop forever; `randrange(0)` raises before reaching it).
    pub fn randbelow(&mut self, n: u32) -> u32 {
        assert!(n > 0, "randbelow needs n > 0");
        let k = u32::BITS - n.leading_zeros();
        loop {
            let r = self.getrandbits(k);
            if r < n {
                return r;
            }
        }
    }

    /// CPython's `random.shuffle(x)`: Fisher–Yates from the back, swapping `x[i]` with
    /// `x[randbelow(i + 1)]` for `i = len − 1` down to 1. The direction and the `randbelow`
    /// bounds decide which outputs go where, so both follow CPython exactly.
    ///
    /// # Panics
    /// If `items` has more than `u32::MAX` elements.
    pub fn shuffle<T>(&mut self, items: &mut [T]) {
        for i in (1..items.len()).rev() {
            let bound = u32::try_from(i + 1).expect("shuffle supports up to u32::MAX items");
            let j = self.randbelow(bound) as usize;
            items.swap(i, j);
        }
    }

    /// numpy's legacy `np.random.random_sample()`: a double in [0, 1) with 53 random bits, from
    /// two outputs `a`, `b` as `((a >> 5)·2²⁶ + (b >> 6)) / 2⁵³` (27 + 26 bits, first output
    /// high). Both products and the division are exact in `f64`, so this is bit-identical.
    pub fn random_sample(&mut self) -> f64 {
        let a = self.next_u32() >> 5;
        let b = self.next_u32() >> 6;
        (f64::from(a) * 67_108_864.0 + f64::from(b)) / 9_007_199_254_740_992.0
    }

    /// numpy's legacy `np.random.uniform(lo, hi)`: `lo + (hi − lo)·u` with `u` from
    /// [`random_sample`](Self::random_sample). The width is computed first and the sum last, in
    /// numpy's order, because another arrangement rounds differently.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let width = hi - lo;
        lo + width * self.random_sample()
    }

    /// numpy's legacy `np.random.standard_normal()` (also `randn`): Marsaglia's polar form of
    /// Box–Muller. Each accepted pair `(x1, x2)` yields two normals: `f·x2` is returned now and
    /// `f·x1` is cached and returned by the next call without drawing. The cache matters: the
    /// reference draws 7 normals per reset (docs/src/reference-facts.md §7.3), an odd number, so
    /// the next reset starts with a cached value.
    ///
    /// The arithmetic is numpy's, operation for operation (`sqrt(-2·ln r² / r²)`). `sqrt` is
    /// exact in IEEE 754; `ln` comes from the platform's libm, the same one numpy calls, so the
    /// result is bit-identical on the same platform.
    pub fn standard_normal(&mut self) -> f64 {
        if let Some(cached) = self.gauss.take() {
            return cached;
        }
        loop {
            let x1 = 2.0 * self.random_sample() - 1.0;
            let x2 = 2.0 * self.random_sample() - 1.0;
            let r2 = x1 * x1 + x2 * x2;
            // Outside the unit disc, or the centre (where ln is undefined): draw again.
            if r2 >= 1.0 || r2 == 0.0 {
                continue;
            }
            let f = (-2.0 * r2.ln() / r2).sqrt();
            self.gauss = Some(f * x1);
            return f * x2;
        }
    }
}

#[cfg(test)]
mod test;
