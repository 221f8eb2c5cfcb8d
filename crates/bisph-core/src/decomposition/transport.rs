//! How the parts of a distributed run talk to each other.
//!
//! A [`Transport`] moves words between parts with one collective operation, an all-to-all
//! exchange: every part calls [`Transport::exchange`] with one message for each part and gets
//! back the message each part sent it. The collectives a run needs (sums, maxima, agreement)
//! are built on it here, so a transport only has to implement that one exchange: over MPI
//! between processes, or [`InProcess`] between threads of one process.
//!
//! Every part must make the same sequence of collective calls; each call returns on a part
//! only once every part has made it.

use super::ExactSum;
use crate::dim::Vector;
use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Instant;

/// The words a part sends to or receives from another.
pub type Message = Vec<u64>;

/// An all-to-all exchange between the parts of a run (see the module documentation).
pub trait Transport: Send + Sync + fmt::Debug {
    /// This part's number, `0..parts()`.
    fn rank(&self) -> usize;

    /// Number of parts.
    fn parts(&self) -> usize;

    /// Sends `outgoing[q]` to part `q` (one message per part, this part's own included) and
    /// returns the messages every part sent to this one, indexed by sender.
    fn exchange(&self, outgoing: Vec<Message>) -> Vec<Message>;

    /// This part stops before the others (an error only it met): they must not wait for it
    /// at their next exchange.
    fn abandon(&self);
}

/// Appends the components of `v` to `out`, bit for bit.
pub fn push_vector<V: Vector>(out: &mut Message, v: V) {
    out.extend((0..V::DIM).map(|k| v.get(k).to_bits()));
}

/// The next value [`push_vector`] or `f64::to_bits` wrote in `words` (NaN past the end).
pub fn read_scalar(words: &mut impl Iterator<Item = u64>) -> f64 {
    words.next().map_or(f64::NAN, f64::from_bits)
}

/// The next vector [`push_vector`] wrote in `words`.
pub fn read_vector<V: Vector>(words: &mut impl Iterator<Item = u64>) -> V {
    let mut v = V::ZERO;
    for k in 0..V::DIM {
        v.set(k, read_scalar(words));
    }
    v
}

/// Every part's `message`, indexed by part.
pub fn all_gather(transport: &dyn Transport, message: Message) -> Vec<Message> {
    transport.exchange(vec![message; transport.parts()])
}

/// Adds every part's `sums` element by element, exactly: on return each part holds the same
/// totals, with the bits of one sum over all the terms ([`ExactSum`]).
pub fn sum_over_parts(transport: &dyn Transport, sums: &mut [ExactSum]) {
    if transport.parts() == 1 {
        return;
    }
    let words: Message = sums.iter().flat_map(|s| s.to_words()).collect();
    let gathered = all_gather(transport, words);
    for (k, sum) in sums.iter_mut().enumerate() {
        let mut total = ExactSum::new();
        for message in &gathered {
            let mut digits = [0u64; ExactSum::WORDS];
            digits.copy_from_slice(&message[k * ExactSum::WORDS..(k + 1) * ExactSum::WORDS]);
            total.merge(&ExactSum::from_words(&digits));
        }
        *sum = total;
    }
}

/// The largest of every part's `value` (NaN when any is NaN).
pub fn max_over_parts(transport: &dyn Transport, value: f64) -> f64 {
    if transport.parts() == 1 {
        return value;
    }
    all_gather(transport, vec![value.to_bits()])
        .iter()
        .map(|m| f64::from_bits(m[0]))
        .fold(f64::NEG_INFINITY, |a, b| {
            if a.is_nan() || b.is_nan() {
                f64::NAN
            } else {
                a.max(b)
            }
        })
}

/// `true` when every part's `value` is.
pub fn all_parts(transport: &dyn Transport, value: bool) -> bool {
    if transport.parts() == 1 {
        return value;
    }
    all_gather(transport, vec![u64::from(value)])
        .iter()
        .all(|m| m[0] == 1)
}

/// What a part's exchanges cost so far ([`Counted`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Traffic {
    /// Exchanges made.
    pub exchanges: u64,
    /// Words sent to other parts.
    pub words_sent: u64,
    /// Wall-clock seconds spent in exchanges (waiting for the other parts included).
    pub seconds: f64,
}

/// A transport that counts its exchanges, the words sent and the time spent in them.
#[derive(Debug)]
pub struct Counted {
    inner: Box<dyn Transport>,
    exchanges: AtomicU64,
    words_sent: AtomicU64,
    nanoseconds: AtomicU64,
}

impl Counted {
    /// Counts the exchanges of `inner`.
    pub fn new(inner: Box<dyn Transport>) -> Self {
        Counted {
            inner,
            exchanges: AtomicU64::new(0),
            words_sent: AtomicU64::new(0),
            nanoseconds: AtomicU64::new(0),
        }
    }

    /// The exchanges so far.
    pub fn traffic(&self) -> Traffic {
        Traffic {
            exchanges: self.exchanges.load(Ordering::Relaxed),
            words_sent: self.words_sent.load(Ordering::Relaxed),
            seconds: self.nanoseconds.load(Ordering::Relaxed) as f64 * 1e-9,
        }
    }
}

impl Transport for Counted {
    fn rank(&self) -> usize {
        self.inner.rank()
    }

    fn abandon(&self) {
        self.inner.abandon();
    }

    fn parts(&self) -> usize {
        self.inner.parts()
    }

    fn exchange(&self, outgoing: Vec<Message>) -> Vec<Message> {
        let start = Instant::now();
        let rank = self.rank();
        let words: usize = outgoing
            .iter()
            .enumerate()
            .filter(|&(q, _)| q != rank)
            .map(|(_, m)| m.len())
            .sum();
        let incoming = self.inner.exchange(outgoing);
        let nanoseconds = start.elapsed().as_nanos() as u64;
        self.exchanges.fetch_add(1, Ordering::Relaxed);
        self.words_sent.fetch_add(words as u64, Ordering::Relaxed);
        self.nanoseconds.fetch_add(nanoseconds, Ordering::Relaxed);
        incoming
    }
}

/// Parts as threads of one process: [`InProcess::connect`] gives one end per part, each to be
/// driven from its own thread. Used to run and test a decomposed simulation without MPI. A
/// part whose thread panics, or that abandons the run, breaks the transport: the others panic
/// at their next exchange instead of waiting for it forever.
pub struct InProcess {
    rank: usize,
    shared: Arc<Shared>,
}

struct Shared {
    parts: usize,
    state: Mutex<Rendezvous>,
    arrived: Condvar,
}

/// The messages in flight and the count of parts at the current meeting point.
struct Rendezvous {
    /// `slots[to][from]`: the message in flight from `from` to `to`.
    slots: Vec<Vec<Message>>,
    waiting: usize,
    /// Meeting points passed so far.
    generation: u64,
    /// A part's thread panicked.
    broken: bool,
}

impl InProcess {
    /// The ends of a transport between `parts` threads, by rank.
    ///
    /// # Panics
    /// When `parts` is zero.
    pub fn connect(parts: usize) -> Vec<InProcess> {
        assert!(parts >= 1, "a transport needs at least one part");
        let shared = Arc::new(Shared {
            parts,
            state: Mutex::new(Rendezvous {
                slots: vec![vec![Vec::new(); parts]; parts],
                waiting: 0,
                generation: 0,
                broken: false,
            }),
            arrived: Condvar::new(),
        });
        (0..parts)
            .map(|rank| InProcess {
                rank,
                shared: Arc::clone(&shared),
            })
            .collect()
    }

    fn lock(&self) -> MutexGuard<'_, Rendezvous> {
        self.shared.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Waits until every part has called it as often as this one.
    fn meet<'a>(&'a self, mut state: MutexGuard<'a, Rendezvous>) -> MutexGuard<'a, Rendezvous> {
        let generation = state.generation;
        state.waiting += 1;
        if state.waiting == self.shared.parts {
            state.waiting = 0;
            state.generation += 1;
            self.shared.arrived.notify_all();
            return state;
        }
        while state.generation == generation {
            assert!(!state.broken, "another part of the run stopped");
            state = self
                .shared
                .arrived
                .wait(state)
                .unwrap_or_else(|e| e.into_inner());
        }
        state
    }
}

impl InProcess {
    /// Breaks the transport (see the type's documentation).
    fn break_off(&self) {
        self.lock().broken = true;
        self.shared.arrived.notify_all();
    }
}

impl Drop for InProcess {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.break_off();
        }
    }
}

impl fmt::Debug for InProcess {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "InProcess({} of {})", self.rank, self.shared.parts)
    }
}

impl Transport for InProcess {
    fn rank(&self) -> usize {
        self.rank
    }

    fn abandon(&self) {
        self.break_off();
    }

    fn parts(&self) -> usize {
        self.shared.parts
    }

    fn exchange(&self, outgoing: Vec<Message>) -> Vec<Message> {
        assert_eq!(outgoing.len(), self.parts(), "one message per part");
        let mut state = self.lock();
        for (to, message) in outgoing.into_iter().enumerate() {
            state.slots[to][self.rank] = message;
        }
        // Every message is in place once all parts meet; each then takes its own row, and
        // nobody writes the next round's messages before all have taken theirs.
        let mut state = self.meet(state);
        let empty = vec![Vec::new(); self.parts()];
        let incoming = std::mem::replace(&mut state.slots[self.rank], empty);
        drop(self.meet(state));
        incoming
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn on_threads<T: Send>(parts: usize, work: impl Fn(&InProcess) -> T + Sync) -> Vec<T> {
        let ends = InProcess::connect(parts);
        std::thread::scope(|scope| {
            let handles: Vec<_> = ends.iter().map(|end| scope.spawn(|| work(end))).collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        })
    }

    /// A part that panics makes the others panic at their next exchange, not wait forever.
    #[test]
    fn a_panicking_part_breaks_the_transport() {
        let ends = InProcess::connect(2);
        let outcomes: Vec<bool> = std::thread::scope(|scope| {
            let handles: Vec<_> = ends
                .into_iter()
                .map(|end| {
                    scope.spawn(move || {
                        if end.rank() == 1 {
                            panic!("a part stops");
                        }
                        end.exchange(vec![Vec::new(); 2]);
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().is_err()).collect()
        });
        assert_eq!(outcomes, [true, true]);
    }

    #[test]
    fn messages_reach_their_part_from_every_sender() {
        let received = on_threads(3, |t| {
            let outgoing = (0..3).map(|q| vec![(10 * t.rank() + q) as u64]).collect();
            let first = t.exchange(outgoing);
            // A second round right after: no message of the first is overwritten early.
            let second = t.exchange(vec![vec![t.rank() as u64 + 100]; 3]);
            (first, second)
        });
        for (rank, (first, second)) in received.iter().enumerate() {
            for (from, message) in first.iter().enumerate() {
                assert_eq!(message, &vec![(10 * from + rank) as u64]);
            }
            for (from, message) in second.iter().enumerate() {
                assert_eq!(message, &vec![from as u64 + 100]);
            }
        }
    }

    #[test]
    fn reductions_agree_on_every_part_and_match_one_sum() {
        let terms: Vec<f64> = (0..300)
            .map(|k| (k as f64 * 0.37).sin() * 10f64.powi(k % 9))
            .collect();
        let whole = super::super::exact_sum(terms.iter().copied());
        let results = on_threads(4, |t| {
            let mut sums = [ExactSum::new(), ExactSum::new()];
            for (k, &x) in terms.iter().enumerate() {
                if k % 4 == t.rank() {
                    sums[0].add(x);
                    sums[1].add(-2.0 * x);
                }
            }
            sum_over_parts(t, &mut sums);
            let max = max_over_parts(t, t.rank() as f64);
            let all = all_parts(t, t.rank() != 2);
            (sums[0].value(), sums[1].value(), max, all)
        });
        for (sum, twice, max, all) in results {
            assert_eq!(sum.to_bits(), whole.to_bits());
            assert_eq!(twice.to_bits(), (-2.0 * whole).to_bits());
            assert_eq!(max, 3.0);
            assert!(!all);
        }
    }
}
