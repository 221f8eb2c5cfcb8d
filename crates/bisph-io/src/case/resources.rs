//! Resource limits: a case that would need more memory than the machine has is refused before
//! anything is allocated.

use crate::case::primitives::{round_bounds, round_elements, Round, RoundKeys};
use crate::case::schema::LoadedCase;

/// Bytes per fluid particle of a running simulation: the fluid arrays (id, position, velocity,
/// density, mass, pressure, acceleration, density rate), the integrator's scratch (staged
/// velocity and density, volume, previous rates, drift, permutation buffers, bounce), the cell
/// grid, the run loop's copy of the last good state, and output temporaries.
pub fn bytes_per_particle(dim: usize) -> u64 {
    let v = 8 * dim as u64;
    let fluid = 4 + 3 * v + 4 * 8;
    let scratch = 4 * v + 5 * 8 + 4;
    let grid = 8;
    // Output and energy temporaries (VTK arrays, heights): measured on the 2-D dam break, the
    // total is within 3% of the 356 bytes per particle its peak resident size grows by.
    let temporaries = 3 * v + 16;
    2 * fluid + scratch + grid + temporaries
}

/// Boundary elements are counted per particle of the wall's surface: bytes per element.
pub fn bytes_per_element(dim: usize) -> u64 {
    let v = 8 * dim as u64;
    // centre, normal, velocity, reference centre and normal, corners (2 in 2-D, 4 in 3-D, twice),
    // area, reference area, reach, pressure, body, corner start, plus the copy of the last good
    // state.
    let corners = if dim == 2 { 2 } else { 4 };
    2 * (5 * v + 2 * corners * v + 4 * 8 + 8)
}

/// Fluid particles a case asks for, from the bounding boxes of its box, polygon, circle,
/// sphere and cylinder blocks at their spacing (blocks read from files are bounded by their
/// files and not counted).
pub fn estimated_particles(loaded: &LoadedCase) -> f64 {
    let c = &loaded.case;
    let d = c.dim as usize;
    let mut total = 0.0;
    for b in &c.fluid_block {
        let dx = b.dx.unwrap_or(c.resolution.dx);
        let round = Round::of_block(b.shape).filter(|r| r.dim() == d);
        let (lo, hi): (Vec<f64>, Vec<f64>) = match (&b.min, &b.max, &b.points) {
            _ if round.is_some() => {
                let keys = RoundKeys {
                    centre: b.centre.as_deref(),
                    radius: b.radius,
                    start: b.start.as_deref(),
                    end: b.end.as_deref(),
                };
                round_bounds(round.expect("a round block"), keys, d)
            }
            (Some(lo), Some(hi), _) => (lo.clone(), hi.clone()),
            (_, _, Some(pts)) if !pts.is_empty() => {
                let mut lo = vec![f64::INFINITY; d];
                let mut hi = vec![f64::NEG_INFINITY; d];
                for p in pts {
                    for k in 0..d.min(p.len()) {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                (lo, hi)
            }
            _ => continue,
        };
        let mut n = 1.0;
        for k in 0..d.min(lo.len()).min(hi.len()) {
            n *= ((hi[k] - lo[k]) / dx).max(0.0) + 1.0;
        }
        total += n;
    }
    total
}

/// Boundary elements a case asks for, from the surfaces of its box, polygon and round walls
/// at `element_over_dx`.
pub fn estimated_elements(loaded: &LoadedCase) -> f64 {
    let c = &loaded.case;
    let d = c.dim as usize;
    let size = c.resolution.dx * c.resolution.element_over_dx;
    let mut total = 0.0;
    for w in &c.wall {
        if let Some(round) = Round::of_wall(w.shape).filter(|r| r.dim() == d) {
            let size = w.element_size.unwrap_or(size);
            total += round_elements(round, RoundKeys::of_wall(w), size) + 1.0;
            continue;
        }
        if let (Some(lo), Some(hi)) = (&w.min, &w.max) {
            let ext: Vec<f64> = lo
                .iter()
                .zip(hi)
                .map(|(a, b)| ((b - a) / size).max(0.0) + 1.0)
                .collect();
            total += if d == 2 || ext.len() < 3 {
                2.0 * ext.iter().sum::<f64>()
            } else {
                2.0 * (ext[0] * ext[1] + ext[1] * ext[2] + ext[0] * ext[2])
            };
        }
        if let Some(pts) = &w.points {
            let mut length = 0.0;
            for pair in pts.windows(2) {
                let (a, b) = (&pair[0], &pair[1]);
                length += a
                    .iter()
                    .zip(b)
                    .map(|(x, y)| (x - y) * (x - y))
                    .sum::<f64>()
                    .sqrt();
            }
            total += length / size + 1.0;
        }
    }
    total
}

/// Estimated bytes a run of the case needs.
pub fn estimated_bytes(loaded: &LoadedCase) -> f64 {
    let d = loaded.case.dim as usize;
    estimated_particles(loaded) * bytes_per_particle(d) as f64
        + estimated_elements(loaded) * bytes_per_element(d) as f64
}

/// Bytes a midpoint step's pair lists may take ([`bisph_core::SimConfig::pair_list_budget`]):
/// half the memory available when the case is built, or
/// [`bisph_core::simulation::PAIR_LIST_BUDGET`] where that is not known.
pub fn pair_list_budget() -> usize {
    available_memory().map_or(bisph_core::simulation::PAIR_LIST_BUDGET, |b| {
        usize::try_from(b / 2).unwrap_or(usize::MAX)
    })
}

/// `MemAvailable` from `/proc/meminfo` in bytes (None where there is no such file).
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_meminfo(&text)
}

/// `MemAvailable` in bytes from the text of `/proc/meminfo`.
pub fn parse_meminfo(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Refuses a case whose estimated memory exceeds what is available, with the estimate.
pub fn check_memory(loaded: &LoadedCase) -> Result<(), String> {
    let Some(available) = available_memory() else {
        return Ok(());
    };
    let needed = estimated_bytes(loaded);
    if needed > available as f64 {
        return Err(format!(
            "{}: the case needs about {:.3} GiB ({:.3e} fluid particles at {} bytes, {:.3e} boundary elements), \
             more than the {:.3} GiB available (MemAvailable); coarsen resolution.dx or shrink the fluid blocks",
            loaded.source,
            needed / (1u64 << 30) as f64,
            estimated_particles(loaded),
            bytes_per_particle(loaded.case.dim as usize),
            estimated_elements(loaded),
            available as f64 / (1u64 << 30) as f64
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meminfo_is_read() {
        let text = "MemTotal:       16000000 kB\nMemFree: 1 kB\nMemAvailable:    8000000 kB\n";
        assert_eq!(parse_meminfo(text), Some(8_000_000 * 1024));
        assert_eq!(parse_meminfo("MemTotal: 5 kB\n"), None);
        assert_eq!(parse_meminfo("MemAvailable: lots\n"), None);
    }
}
