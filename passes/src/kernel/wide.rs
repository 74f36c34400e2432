//! 64-bit atomics over the simulator's 32-bit words.
//!
//! WGSL's `atomic<u64>` (naga capability `SHADER_INT64_ATOMIC_MIN_MAX`)
//! stores each value in two consecutive 32-bit words, low word first, as
//! GPUs lay storage out little-endian. Lipp's visibility buffer packs depth
//! and strand id into one 64-bit `atomicMin` (Lipp §3.1, "64-bit G-buffers"),
//! and the roofline bench measures that operation, so the simulator needs
//! the same operation: slot `i` of a [`Words`] is words `2i` (low) and
//! `2i + 1` (high).
//!
//! Where the slot is 8-byte aligned on a little-endian host (the usual case:
//! the CPU backend's allocations and the plan's placements are aligned far
//! beyond 8 bytes) the pair is viewed as one [`AtomicU64`] and the operation
//! is a single hardware atomic. Otherwise (a misaligned slice, a big-endian
//! host) the slot's two words are updated under one of a fixed set of
//! striped locks, which is atomic with respect to every other 64-bit
//! operation of this module on the same slot.
//!
//! The rule that makes either path sound is WGSL's own: during a pass a
//! buffer is either an `array<atomic<u64>>` or an array of 32-bit words,
//! never both. Kernels must not mix these 64-bit operations with 32-bit
//! accesses to the same words within one dispatch; between passes the
//! backend's join of the workgroups orders everything (Rust's memory model
//! forbids only *unsynchronised* mixed-size accesses).

use super::Words;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// Locks of the fallback path, picked by slot address.
static STRIPES: [Mutex<()>; 64] = [const { Mutex::new(()) }; 64];

/// How one slot is reached.
enum Slot<'a> {
    /// An aligned pair viewed as one 64-bit atomic.
    Native(&'a AtomicU64),
    /// Word index of the low half, to be updated under a stripe lock.
    Locked(usize),
}

impl<'a> Words<'a> {
    /// Number of 64-bit slots (whole word pairs).
    pub fn len_u64(&self) -> usize {
        self.words.len() / 2
    }

    fn slot(&self, i: usize) -> Option<Slot<'a>> {
        let lo = i.checked_mul(2).filter(|&lo| lo + 1 < self.words.len());
        let Some(lo) = lo else {
            self.oob.fetch_add(1, Relaxed);
            return None;
        };
        // Derived from the whole slice, so the pointer may cover both words.
        let ptr = self.words[lo..].as_ptr();
        let aligned = (ptr as usize).is_multiple_of(std::mem::align_of::<AtomicU64>());
        if cfg!(target_endian = "little") && aligned {
            // SAFETY: `ptr` points at two live, consecutive `AtomicU32`s of
            // `self.words` (checked above), which lives for `'a`; it is
            // aligned for `AtomicU64` (checked above); `AtomicU32` is an
            // `UnsafeCell`, so writing through a shared borrow is allowed;
            // and the module contract (no 32-bit access to these words in
            // the same dispatch) rules out unsynchronised mixed-size access.
            Some(Slot::Native(unsafe {
                AtomicU64::from_ptr(ptr as *mut u64)
            }))
        } else {
            Some(Slot::Locked(lo))
        }
    }

    fn locked<R>(&self, lo: usize, f: impl FnOnce(u64) -> (u64, R)) -> R {
        let stripe = &STRIPES[(self.words[lo..].as_ptr() as usize / 8) % STRIPES.len()];
        let _guard = stripe.lock().unwrap_or_else(|e| e.into_inner());
        let old = u64::from(self.words[lo].load(Relaxed))
            | (u64::from(self.words[lo + 1].load(Relaxed)) << 32);
        let (new, r) = f(old);
        if new != old {
            self.words[lo].store(new as u32, Relaxed);
            self.words[lo + 1].store((new >> 32) as u32, Relaxed);
        }
        r
    }

    /// 64-bit `atomicMin` on slot `i`; returns the previous value
    /// (`u64::MAX` out of range, where the write is dropped and counted).
    pub fn fetch_min_u64(&self, i: usize, v: u64) -> u64 {
        match self.slot(i) {
            None => u64::MAX,
            Some(Slot::Native(a)) => a.fetch_min(v, Relaxed),
            Some(Slot::Locked(lo)) => self.locked(lo, |old| (old.min(v), old)),
        }
    }

    /// Atomic 64-bit load of slot `i` (0 out of range).
    pub fn load_u64(&self, i: usize) -> u64 {
        match self.slot(i) {
            None => 0,
            Some(Slot::Native(a)) => a.load(Relaxed),
            Some(Slot::Locked(lo)) => self.locked(lo, |old| (old, old)),
        }
    }

    /// Atomic 64-bit store to slot `i` (dropped out of range).
    pub fn store_u64(&self, i: usize, v: u64) {
        match self.slot(i) {
            None => {}
            Some(Slot::Native(a)) => a.store(v, Relaxed),
            Some(Slot::Locked(lo)) => self.locked(lo, |_| (v, ())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicU32;

    fn splitmix(mut x: u64) -> u64 {
        x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
        x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        x ^ (x >> 31)
    }

    /// Four threads race `fetch_min_u64` over a small buffer; every slot
    /// must end at the sequential minimum, whichever path the slot takes.
    fn race(words: &[AtomicU32]) {
        let oob = AtomicU64::new(0);
        let w = Words::new(words, &oob);
        let slots = w.len_u64();
        for s in 0..slots {
            w.store_u64(s, u64::MAX);
        }
        let per_thread = 20_000u64;
        std::thread::scope(|scope| {
            for t in 0..4u64 {
                scope.spawn(move || {
                    for k in 0..per_thread {
                        let h = splitmix(t * per_thread + k);
                        w.fetch_min_u64((h % slots as u64) as usize, splitmix(h));
                    }
                });
            }
        });
        let mut expect = vec![u64::MAX; slots];
        for n in 0..4 * per_thread {
            let h = splitmix(n);
            let s = (h % slots as u64) as usize;
            expect[s] = expect[s].min(splitmix(h));
        }
        for (s, &e) in expect.iter().enumerate() {
            assert_eq!(w.load_u64(s), e, "slot {s}");
            // Low word first, as WGSL lays out atomic<u64>.
            assert_eq!(w.load(2 * s), e as u32);
            assert_eq!(w.load(2 * s + 1), (e >> 32) as u32);
        }
        assert_eq!(oob.load(Relaxed), 0);
    }

    #[test]
    fn concurrent_min_matches_sequential_min_on_both_paths() {
        let words: Vec<AtomicU32> = (0..65).map(|_| AtomicU32::new(0)).collect();
        let offset = usize::from(!(words.as_ptr() as usize).is_multiple_of(8));
        // Aligned: one native 64-bit atomic per slot.
        race(&words[offset..offset + 64]);
        // Misaligned by one word: the striped-lock path.
        race(&words[offset + 1..offset + 65]);
    }

    #[test]
    fn out_of_range_is_dropped_and_counted() {
        let words: Vec<AtomicU32> = (0..5).map(|_| AtomicU32::new(7)).collect();
        let oob = AtomicU64::new(0);
        let w = Words::new(&words, &oob);
        assert_eq!(w.len_u64(), 2);
        // Slot 2 would need word 5: the odd trailing word is no slot.
        assert_eq!(w.fetch_min_u64(2, 0), u64::MAX);
        assert_eq!(w.load_u64(usize::MAX), 0);
        assert_eq!(oob.load(Relaxed), 2);
        assert_eq!(w.load(4), 7);
        assert_eq!(w.fetch_min_u64(1, 3), 7 | (7 << 32));
        assert_eq!(w.load_u64(1), 3);
    }
}
