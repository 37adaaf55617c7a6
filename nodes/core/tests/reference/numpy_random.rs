//! numpy's `default_rng(seed).uniform(-1, 1, size=8)` stream, re-implemented so the port can
//! take the very actions the reference's random-policy episodes took
//! (`tests/reference/data/random_returns.json`): a `SeedSequence` of one integer word feeding a
//! PCG64 (128-bit LCG, XSL-RR output). Facts from numpy's documented algorithms; the recorded
//! first action of every episode checks this module bit for bit.

/// SeedSequence's hashing constants (numpy/random/bit_generator.pyx).
const INIT_A: u32 = 0x43b0_d7e5;
const MULT_A: u32 = 0x931e_8875;
const INIT_B: u32 = 0x8b51_f9dd;
const MULT_B: u32 = 0x58f3_8ded;
const MIX_MULT_L: u32 = 0xca01_f9dd;
const MIX_MULT_R: u32 = 0x4973_f715;
const XSHIFT: u32 = 16;
const POOL_SIZE: usize = 4;

/// PCG64's LCG multiplier.
const PCG_MULTIPLIER: u128 = 0x2360_ed05_1fc6_5da4_4385_df64_9fcc_f645;

/// SeedSequence's hash step: the value mixed with the running constant, which advances by
/// `multiplier` (MULT_A while the pool is filled, MULT_B while the state is drawn from it).
fn hash(value: u32, constant: &mut u32, multiplier: u32) -> u32 {
    let mut value = value ^ *constant;
    *constant = constant.wrapping_mul(multiplier);
    value = value.wrapping_mul(*constant);
    value ^ (value >> XSHIFT)
}

/// The entropy pool of `SeedSequence(seed)` for a seed below 2³².
fn seed_sequence_pool(seed: u32) -> [u32; POOL_SIZE] {
    let mut constant = INIT_A;
    let mix = |x: u32, y: u32| {
        let r = MIX_MULT_L
            .wrapping_mul(x)
            .wrapping_sub(MIX_MULT_R.wrapping_mul(y));
        r ^ (r >> XSHIFT)
    };
    let entropy = [seed];
    let mut pool = [0u32; POOL_SIZE];
    for (i, slot) in pool.iter_mut().enumerate() {
        *slot = hash(entropy.get(i).copied().unwrap_or(0), &mut constant, MULT_A);
    }
    for src in 0..POOL_SIZE {
        for dst in 0..POOL_SIZE {
            if src != dst {
                let hashed = hash(pool[src], &mut constant, MULT_A);
                pool[dst] = mix(pool[dst], hashed);
            }
        }
    }
    pool
}

/// `SeedSequence(seed).generate_state(4, uint64)`.
fn generate_state(seed: u32) -> [u64; 4] {
    let pool = seed_sequence_pool(seed);
    let mut constant = INIT_B;
    let words: [u32; 8] = std::array::from_fn(|i| hash(pool[i % POOL_SIZE], &mut constant, MULT_B));
    std::array::from_fn(|k| words[2 * k] as u64 | (words[2 * k + 1] as u64) << 32)
}

/// `numpy.random.default_rng(seed)`: PCG64.
pub struct DefaultRng {
    state: u128,
    increment: u128,
}

impl DefaultRng {
    pub fn new(seed: u32) -> DefaultRng {
        let s = generate_state(seed);
        let initial_state = (s[0] as u128) << 64 | s[1] as u128;
        let sequence = (s[2] as u128) << 64 | s[3] as u128;
        let mut rng = DefaultRng {
            state: 0,
            increment: sequence << 1 | 1,
        };
        rng.advance();
        rng.state = rng.state.wrapping_add(initial_state);
        rng.advance();
        rng
    }

    fn advance(&mut self) {
        self.state = self
            .state
            .wrapping_mul(PCG_MULTIPLIER)
            .wrapping_add(self.increment);
    }

    pub fn next_u64(&mut self) -> u64 {
        self.advance();
        let rotation = (self.state >> 122) as u32;
        (((self.state >> 64) as u64) ^ (self.state as u64)).rotate_right(rotation)
    }

    /// `uniform(low, high)`: low + (high − low)·(53 random bits / 2⁵³).
    pub fn uniform(&mut self, low: f64, high: f64) -> f64 {
        let unit = (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        low + (high - low) * unit
    }

    /// One reference action of the random policy: `uniform(-1, 1, size=8)`.
    pub fn action(&mut self) -> [f64; 8] {
        std::array::from_fn(|_| self.uniform(-1.0, 1.0))
    }
}
