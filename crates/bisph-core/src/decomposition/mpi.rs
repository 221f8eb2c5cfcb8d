//! The [`Transport`] between processes: MPI (the `mpi` feature, through rsmpi).
//!
//! One exchange is two MPI all-to-all calls: the message lengths (`MPI_Alltoall`), then the
//! words (`MPI_Alltoallv`).

use super::transport::{Message, Transport};
use mpi::datatype::{Partition, PartitionMut};
use mpi::environment::Universe;
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::traits::CommunicatorCollectives;
use mpi::Count;
use std::fmt;
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicBool, Ordering};

/// The processes of an MPI job as the parts of a run: rank `r` of `MPI_COMM_WORLD` is part
/// `r`. MPI is finalised when it is dropped, unless this part abandoned the run: then the
/// process ends without finalising, and the launcher ends the others.
pub struct MpiTransport {
    world: SimpleCommunicator,
    universe: ManuallyDrop<Universe>,
    abandoned: AtomicBool,
}

// SAFETY: MPI is initialised at the `Funneled` level, and a part calls its transport only
// from the thread that drives its simulation (rate sweeps on the thread pool never do), so
// no two threads make MPI calls at once.
unsafe impl Send for MpiTransport {}
unsafe impl Sync for MpiTransport {}

impl MpiTransport {
    /// Initialises MPI, or returns `None` when it was initialised already in this process.
    pub fn initialise() -> Option<Self> {
        let (universe, _) = mpi::initialize_with_threading(mpi::Threading::Funneled)?;
        Some(MpiTransport {
            world: universe.world(),
            universe: ManuallyDrop::new(universe),
            abandoned: AtomicBool::new(false),
        })
    }
}

impl Drop for MpiTransport {
    fn drop(&mut self) {
        if !self.abandoned.load(Ordering::SeqCst) {
            // SAFETY: dropped once, here, and not used after.
            unsafe { ManuallyDrop::drop(&mut self.universe) };
        }
    }
}

impl fmt::Debug for MpiTransport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "MpiTransport({} of {})", self.rank(), self.parts())
    }
}

/// Offsets of consecutive blocks of the given lengths.
fn offsets(counts: &[Count]) -> Vec<Count> {
    counts
        .iter()
        .scan(0, |start, &n| {
            let this = *start;
            *start += n;
            Some(this)
        })
        .collect()
}

impl Transport for MpiTransport {
    fn rank(&self) -> usize {
        self.world.rank() as usize
    }

    fn parts(&self) -> usize {
        self.world.size() as usize
    }

    fn abandon(&self) {
        self.abandoned.store(true, Ordering::SeqCst);
    }

    fn exchange(&self, outgoing: Vec<Message>) -> Vec<Message> {
        assert_eq!(outgoing.len(), self.parts(), "one message per part");
        let send_counts: Vec<Count> = outgoing
            .iter()
            .map(|m| Count::try_from(m.len()).expect("a message of fewer than 2^31 words"))
            .collect();
        let mut receive_counts = vec![0 as Count; self.parts()];
        self.world
            .all_to_all_into(&send_counts[..], &mut receive_counts[..]);
        let words: Vec<u64> = outgoing.concat();
        let total: usize = receive_counts.iter().map(|&n| n as usize).sum();
        let mut received = vec![0u64; total];
        let send_offsets = offsets(&send_counts);
        let receive_offsets = offsets(&receive_counts);
        {
            let send = Partition::new(&words[..], &send_counts[..], &send_offsets[..]);
            let mut receive =
                PartitionMut::new(&mut received[..], &receive_counts[..], &receive_offsets[..]);
            self.world.all_to_all_varcount_into(&send, &mut receive);
        }
        receive_offsets
            .iter()
            .zip(&receive_counts)
            .map(|(&start, &n)| received[start as usize..(start + n) as usize].to_vec())
            .collect()
    }
}
