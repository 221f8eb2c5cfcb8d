//! A simulation as one part of a run split over several ([`Simulation::part_of`]).
//!
//! The fluid is divided into regions by recursive coordinate bisection ([`bisect`]); a part
//! owns the particles in its region and holds copies of the others' particles within reach of
//! it (its halo). Its particles are stored owned first, then the halo by sending part.
//!
//! Every part runs the same steps. A particle's rates depend only on the particles within
//! reach, in an order fixed by the cell lattice and the global ids, so each part computes its
//! own particles' rates with the bits of a single run. Everything else stays identical through
//! these rules:
//! - updates that act on one particle at a time (kicks, drifts, bounces, gamma) run on the
//!   halo too, on the same inputs, so they give the owners' bits;
//! - the results of neighbour sums (rates, summation densities) are copied from the owners to
//!   the halos right after they are computed ([`Simulation::refresh_halo`]);
//! - sums over particles or wall elements are exact ([`ExactSum`]) over what each part owns
//!   (a wall element belongs to the part whose region holds its centre) and added over the
//!   parts, maxima are taken over the parts, and the decisions that follow (time step,
//!   neighbour-list rebuilds, midpoint convergence, errors) are the same on every part;
//! - at each neighbour-list rebuild, the regions are cut again when the parts' work has
//!   drifted apart, particles that left their region move to its owner, and the halos
//!   are selected again ([`Simulation::repartition`]).

use super::part_state::{
    halo_words, set_halo, BadParticle, HaloFields, Part, PartLayout, REBALANCE,
};
use super::Simulation;
use crate::decomposition::{
    all_gather, all_parts, bisect, max_over_parts, push_vector, read_vector, select_halos,
    sum_over_parts, Bounds, Counted, ExactSum, Message, Traffic, Transport,
};
use crate::dim::Vector;
use crate::particles::{Fluid, PermuteScratch};

impl<V: Vector> Simulation<V> {
    /// The part `transport.rank()` of a run of the simulation `whole` split into
    /// `transport.parts()` parts (see the module documentation). Every part must be built
    /// at once, each on its own thread or process with its end of the transport: building
    /// exchanges the halos. `whole` holds the whole fluid, just built or restored from a
    /// checkpoint (then with its Verlet list, which the parts take over): its next steps and
    /// those of its parts give the same bits.
    ///
    /// # Panics
    /// When `whole` is itself a part.
    pub fn part_of(whole: &Simulation<V>, transport: Box<dyn Transport>) -> Simulation<V> {
        assert!(whole.part.is_none(), "a part cannot be split again");
        let config = &whole.config;
        let period = config.periodicity;
        let mut domain: Bounds<V> = Bounds::everywhere();
        for k in (0..V::DIM).filter(|&k| period.is_periodic(k)) {
            domain.lo.set(k, period.min.get(k));
            domain.hi.set(k, period.min.get(k) + period.length.get(k));
        }
        let f = &whole.fluid;
        let weights = whole.work_weights(f.len());
        let decomposition = bisect(&f.position, &weights, &f.id, transport.parts(), domain);
        let rank = transport.rank();
        let own: Vec<u32> = (0..f.len() as u32)
            .filter(|&i| decomposition.owner(f.position[i as usize]) == rank)
            .collect();
        let mut fluid = f.clone();
        fluid.hold_earlier_rates();
        fluid.permute(&own, &mut PermuteScratch::default());
        let reach = 2.0 * (config.kernel.support + whole.walls.elements.max_reach);
        let mut part = Simulation::new_part(whole, fluid);
        part.part = Some(Part {
            transport: Counted::new(transport),
            decomposition,
            owned: own.len(),
            send: Vec::new(),
            reach,
            departed: 0,
            rebalances: 0,
        });
        part.select_halo();
        // The Verlet list of the whole, over this part's particles (the halo's included).
        let origin = whole.neighbour_list_origin().map(|origin| {
            // Indexed by id (with gaps where particles left the domain).
            let slots = f.id.iter().max().map_or(0, |&m| m as usize + 1);
            let mut at_id = vec![V::ZERO; slots];
            for (&id, &o) in f.id.iter().zip(origin) {
                at_id[id as usize] = o;
            }
            let ids = &part.fluid.id;
            ids.iter().map(|&id| at_id[id as usize]).collect::<Vec<V>>()
        });
        part.restore_neighbour_list(origin.as_deref());
        part
    }

    /// `true` for a part of a split run ([`Simulation::part_of`]).
    pub fn is_part(&self) -> bool {
        self.part.is_some()
    }

    /// Number of parts of the run (1 for a whole simulation).
    pub fn parts(&self) -> usize {
        self.part.as_ref().map_or(1, |p| p.transport.parts())
    }

    /// This part's number (0 for a whole simulation).
    pub fn rank(&self) -> usize {
        self.part.as_ref().map_or(0, |p| p.transport.rank())
    }

    /// Number of particles this simulation owns: they are stored first in
    /// [`Simulation::fluid`], before the halo (all of them for a whole simulation).
    pub fn owned_len(&self) -> usize {
        self.part.as_ref().map_or(self.fluid.len(), |p| p.owned)
    }

    /// Number of halo particles this part holds (0 for a whole simulation).
    pub fn halo_len(&self) -> usize {
        self.fluid.len() - self.owned_len()
    }

    /// What this part's exchanges with the others cost so far (`None` for a whole
    /// simulation).
    pub fn traffic(&self) -> Option<Traffic> {
        self.part.as_ref().map(|p| p.transport.traffic())
    }

    /// This part's layout in its split (`None` for a whole simulation): with the fluid arrays
    /// of the same moment, what [`Simulation::restore_part_layout`] needs to bring the part
    /// back to it.
    pub fn part_layout(&self) -> Option<PartLayout<V>> {
        self.part.as_ref().map(|p| PartLayout {
            decomposition: p.decomposition.clone(),
            owned: p.owned,
            send: p.send.clone(),
        })
    }

    /// Puts back a layout taken by [`Simulation::part_layout`] on this same part, after its
    /// fluid arrays of that moment were put back: each part of the run must put back the
    /// layout of the same moment. Returns `false`, changing nothing, for a whole simulation
    /// or a layout that does not fit the fluid arrays.
    pub fn restore_part_layout(&mut self, layout: &PartLayout<V>) -> bool {
        let n = self.fluid.len();
        let Some(part) = &mut self.part else {
            return false;
        };
        let fits = layout.owned <= n
            && layout.send.len() == part.transport.parts()
            && layout
                .send
                .iter()
                .flatten()
                .all(|&i| (i as usize) < layout.owned);
        if !fits {
            return false;
        }
        part.decomposition.clone_from(&layout.decomposition);
        part.owned = layout.owned;
        part.send.clone_from(&layout.send);
        self.mark_elements_in_reach();
        true
    }

    /// Every part's `words`, in part order (every part must call it; a whole simulation gets
    /// its own back).
    pub fn gather_over_parts(&self, words: Message) -> Vec<Message> {
        match &self.part {
            Some(part) => all_gather(&part.transport, words),
            None => vec![words],
        }
    }

    /// Tells the other parts that this one stops here, on an error only it met: they do not
    /// wait for it (see [`Transport::abandon`]). Nothing to do for a whole simulation.
    pub fn abandon_split(&self) {
        if let Some(part) = &self.part {
            part.transport.abandon();
        }
    }

    /// Each of `flags` set where it is set on at least one part, in one exchange (every part
    /// must call it).
    pub fn on_any_part<const N: usize>(&self, flags: [bool; N]) -> [bool; N] {
        let Some(part) = &self.part else {
            return flags;
        };
        let mut any = [false; N];
        for message in all_gather(&part.transport, flags.map(u64::from).to_vec()) {
            for (a, &word) in any.iter_mut().zip(&message) {
                *a |= word == 1;
            }
        }
        any
    }

    /// Number of times the regions of a split run were cut again since it was split (0 for a
    /// whole simulation).
    pub fn rebalances(&self) -> u64 {
        self.part.as_ref().map_or(0, |p| p.rebalances)
    }

    /// Number of particles this part has handed to other parts since it was built (0 for a
    /// whole simulation).
    pub fn departed(&self) -> u64 {
        self.part.as_ref().map_or(0, |p| p.departed)
    }

    /// The own particles of every part, in increasing id, with their whole records (a whole
    /// simulation gives its own particles). Every part must call it, and each gets them all.
    pub fn gathered_fluid(&self) -> Fluid<V> {
        self.gathered().0
    }

    /// [`Simulation::gathered_fluid`], and where the Verlet list in use was built for each of
    /// those particles ([`Simulation::neighbour_list_origin`]), in the same order: the state
    /// of the whole run, which a whole simulation restores ([`Simulation::restore_neighbour_list`])
    /// to continue with the same bits, split again or not.
    pub fn gathered(&self) -> (Fluid<V>, Option<Vec<V>>) {
        let origin = self.neighbour_list_origin();
        let (mut fluid, mut built_at) = match &self.part {
            None => (self.fluid.clone(), origin.map(<[V]>::to_vec)),
            Some(part) => {
                let owned = 0..part.owned;
                let mut words = Vec::new();
                self.fluid.encode(owned.clone(), &mut words);
                let mut fluid = Fluid::default();
                for words in all_gather(&part.transport, words) {
                    fluid.append_encoded(&words);
                }
                // Every part holds a list, or none does (they are built at the same steps).
                let built_at = origin.map(|origin| {
                    let mut words = Vec::new();
                    for &o in &origin[owned] {
                        push_vector(&mut words, o);
                    }
                    let gathered = all_gather(&part.transport, words).concat();
                    let mut next = gathered.into_iter();
                    (0..fluid.len())
                        .map(|_| read_vector(&mut next))
                        .collect::<Vec<V>>()
                });
                (fluid, built_at)
            }
        };
        let mut by_id: Vec<u32> = (0..fluid.len() as u32).collect();
        by_id.sort_unstable_by_key(|&i| fluid.id[i as usize]);
        fluid.permute(&by_id, &mut PermuteScratch::default());
        if let Some(points) = &mut built_at {
            *points = by_id.iter().map(|&i| points[i as usize]).collect();
        }
        (fluid, built_at)
    }

    /// The wall pressures of every element, each from the part that counts it in sums over
    /// the elements ([`Simulation::element_counter`]): a part evaluates only those within
    /// reach of its region. Every part must call it, and each gets them all.
    pub fn gathered_wall_pressures(&self) -> Vec<f64> {
        let mut pressure = self.walls.elements.pressure.clone();
        let Some(part) = &self.part else {
            return pressure;
        };
        let counts = self.element_counter();
        let mut words = Vec::new();
        for (j, p) in pressure.iter().enumerate().filter(|&(j, _)| counts(j)) {
            words.extend([j as u64, p.to_bits()]);
        }
        for message in all_gather(&part.transport, words) {
            for pair in message.chunks_exact(2) {
                pressure[pair[0] as usize] = f64::from_bits(pair[1]);
            }
        }
        pressure
    }

    /// Adds `sums` over the parts (nothing to do for a whole simulation).
    pub(crate) fn sum_over_parts(&self, sums: &mut [ExactSum]) {
        if let Some(part) = &self.part {
            sum_over_parts(&part.transport, sums);
        }
    }

    /// The sum of every part's `value` (exact; the value itself for a whole simulation).
    pub fn total_over_parts(&self, value: f64) -> f64 {
        let mut sum = [ExactSum::new()];
        sum[0].add(value);
        self.sum_over_parts(&mut sum);
        sum[0].value()
    }

    /// Number of fluid particles of the whole run (the own particles of every part).
    pub fn fluid_count(&self) -> usize {
        self.total_over_parts(self.owned_len() as f64) as usize
    }

    /// `sum f(i)` over the particles of every part, each counted by its owner, exactly.
    pub(crate) fn sum_owned(&self, f: impl Fn(usize) -> f64 + Sync) -> f64 {
        let mut sum = [crate::energy::exact_partial_sum(self.owned_len(), f)];
        self.sum_over_parts(&mut sum);
        sum[0].value()
    }

    /// The largest `value` over the parts (the value itself for a whole simulation).
    pub fn max_over_parts(&self, value: f64) -> f64 {
        match &self.part {
            Some(part) => max_over_parts(&part.transport, value),
            None => value,
        }
    }

    /// `true` when `value` holds on every part.
    pub(crate) fn on_all_parts(&self, value: bool) -> bool {
        match &self.part {
            Some(part) => all_parts(&part.transport, value),
            None => value,
        }
    }

    /// Whether this simulation counts wall element `j` in sums over the elements: the part
    /// whose region holds its centre does (a whole simulation counts every element).
    pub(crate) fn element_counter(&self) -> impl Fn(usize) -> bool + '_ {
        let centres = &self.walls.elements.centre;
        move |j| self.owns_point(centres[j])
    }

    /// Whether this simulation samples at the point `x`: the part whose region holds it does
    /// (a whole simulation samples everywhere).
    pub(crate) fn owns_point(&self, x: V) -> bool {
        self.part.as_ref().is_none_or(|part| {
            let x = self.config.periodicity.wrap(x);
            part.decomposition.owner(x) == part.transport.rank()
        })
    }

    /// Marks the wall elements whose pressure this part needs
    /// ([`crate::walls::BoundaryElements::in_reach`]): those within a kernel support, an
    /// element's reach and two drift limits of its region, where its own particles are. Across
    /// periodic axes every element is kept. Nothing to do for a whole simulation.
    pub(crate) fn mark_elements_in_reach(&mut self) {
        let Some(part) = &self.part else {
            return;
        };
        let drift_limit = self.drift_limit();
        let e = &mut self.walls.elements;
        if self.config.periodicity.any() {
            e.in_reach.clear();
            return;
        }
        let region = part.decomposition.regions()[part.transport.rank()];
        let reach = self.config.kernel.support + e.max_reach + 2.0 * drift_limit;
        let (centres, in_reach) = (&e.centre, &mut e.in_reach);
        in_reach.clear();
        in_reach.extend(
            centres
                .iter()
                .map(|&c| region.distance_squared(c) <= reach * reach),
        );
    }

    /// Of the bad particles of every part, the one with the lowest id.
    pub(crate) fn first_bad_over_parts(&self, bad: Option<BadParticle>) -> Option<BadParticle> {
        let Some(part) = &self.part else {
            return bad;
        };
        let words = bad.map(BadParticle::to_words).unwrap_or_default();
        all_gather(&part.transport, words)
            .iter()
            .filter(|m| !m.is_empty())
            .map(|m| BadParticle::from_words(m))
            .min_by_key(|b| b.id())
    }

    /// Copies `fields` of every halo particle from its owner (nothing to do for a whole
    /// simulation).
    pub(crate) fn refresh_halo(&mut self, fields: HaloFields) {
        let Some(part) = &self.part else {
            return;
        };
        let f = &mut self.fluid;
        let outgoing = part
            .send
            .iter()
            .map(|indices| {
                let mut words = Vec::new();
                for &i in indices {
                    halo_words(f, i as usize, fields, &mut words);
                }
                words
            })
            .collect();
        let incoming = part.transport.exchange(outgoing);
        let mut slot = part.owned;
        for words in &incoming {
            let mut next = words.iter().copied();
            while next.len() > 0 {
                set_halo(f, slot, fields, &mut next);
                slot += 1;
            }
        }
        debug_assert_eq!(slot, f.len(), "every halo particle refreshed");
    }

    /// The work of each of the first `n` particles, the weights of the bisection: one plus
    /// its pairs in the Verlet list in use (the pairs a sweep visits), or one without a
    /// list. Whole numbers, so their sums are exact.
    fn work_weights(&self, n: usize) -> Vec<f64> {
        let s = &self.scratch;
        if s.candidates_valid && s.skin > 0.0 {
            let counts = s.candidates.pair_counts();
            counts[..n].iter().map(|&c| 1.0 + c as f64).collect()
        } else {
            vec![1.0; n]
        }
    }

    /// Cuts the regions again, by recursive coordinate bisection of every part's own particles
    /// weighted by their work ([`Simulation::work_weights`]), when the parts' loads (their
    /// summed weights) are further apart than [`REBALANCE`] allows. Every part decides and
    /// cuts from the same gathered data, so all reach the same regions.
    fn rebalance(&mut self) {
        let Some(part) = &self.part else {
            return;
        };
        let weights = self.work_weights(part.owned);
        let load: f64 = weights.iter().sum();
        let loads: Vec<f64> = all_gather(&part.transport, vec![load.to_bits()])
            .iter()
            .map(|m| f64::from_bits(m[0]))
            .collect();
        if !REBALANCE.should_rebalance(&loads) {
            return;
        }
        let f = &self.fluid;
        let mut words = Vec::new();
        for (i, w) in weights.iter().enumerate() {
            words.extend([u64::from(f.id[i]), w.to_bits()]);
            push_vector(&mut words, f.position[i]);
        }
        let gathered = all_gather(&part.transport, words).concat();
        let (mut points, mut ids, mut weights) = (Vec::new(), Vec::new(), Vec::new());
        for record in gathered.chunks_exact(2 + V::DIM) {
            ids.push(record[0] as u32);
            weights.push(f64::from_bits(record[1]));
            points.push(read_vector(&mut record[2..].iter().copied()));
        }
        let Some(part) = &mut self.part else {
            return;
        };
        let domain = *part.decomposition.domain();
        part.decomposition = bisect(&points, &weights, &ids, part.transport.parts(), domain);
        part.rebalances += 1;
    }

    /// Moves the particles that left this part's region to their owners, stores the own
    /// particles in the cell grid's order when `sort`, and selects the halo again (the
    /// particles of other parts within the reach and two drift limits of the region). Nothing to do
    /// for a whole simulation.
    pub(crate) fn repartition(&mut self, sort: bool) {
        self.rebalance();
        let Some(part) = &self.part else {
            return;
        };
        let rank = part.transport.rank();
        let scratch = &mut self.scratch.permute;
        let f = &mut self.fluid;
        f.truncate(part.owned);
        let owners = part.decomposition.owners(&f.position);
        let mut outgoing = vec![Vec::new(); part.transport.parts()];
        for (i, &owner) in owners.iter().enumerate() {
            if owner != rank {
                f.encode([i], &mut outgoing[owner]);
            }
        }
        let staying: Vec<u32> = (0..f.len() as u32)
            .filter(|&i| owners[i as usize] == rank)
            .collect();
        let departed = (f.len() - staying.len()) as u64;
        f.permute(&staying, scratch);
        for words in part.transport.exchange(outgoing) {
            f.append_encoded(&words);
        }
        if sort {
            self.fluid_grid.rebuild_keyed(&f.position, &f.id);
            f.permute(self.fluid_grid.sorted_items(), scratch);
        }
        if let Some(part) = &mut self.part {
            part.owned = f.len();
            part.departed += departed;
        }
        self.select_halo();
    }

    /// Selects the halo of the own particles and appends it (see the module documentation).
    fn select_halo(&mut self) {
        let drift_limit = self.drift_limit();
        let Some(part) = &mut self.part else {
            return;
        };
        let (rank, parts) = (part.transport.rank(), part.transport.parts());
        let f = &mut self.fluid;
        // Own and halo particles may each move up to the drift limit while the lists are kept.
        let width = part.reach + 2.0 * drift_limit;
        let period = self.config.periodicity;
        let owners = vec![rank; part.owned];
        let halos = select_halos(
            &part.decomposition,
            &f.position,
            &f.id,
            &owners,
            width,
            &period,
        );
        // The periodic cell grid finds the images itself: each particle is sent once,
        // where it is stored, and a part's own images need no copy.
        part.send = halos
            .into_iter()
            .enumerate()
            .map(|(q, entries)| {
                let mut indices: Vec<u32> = if q == rank {
                    Vec::new()
                } else {
                    entries.iter().map(|e| e.index as u32).collect()
                };
                indices.dedup();
                indices
            })
            .collect();
        let outgoing: Vec<Message> = part
            .send
            .iter()
            .map(|indices| {
                let mut words = Vec::new();
                f.encode(indices.iter().map(|&i| i as usize), &mut words);
                words
            })
            .collect();
        debug_assert_eq!(outgoing.len(), parts);
        for words in part.transport.exchange(outgoing) {
            f.append_encoded(&words);
        }
    }
}
