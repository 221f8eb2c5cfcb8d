//! A small VTK XML writer (`.vtu` unstructured grids, `.pvtu` indices of pieces written by
//! several processes, and `.pvd` collections).
//!
//! Files use the "appended" raw binary layout (`header_type="UInt64"`,
//! little endian) that ParaView and VTK read directly. Every file is first
//! written to `<path>.tmp` and then renamed onto `path`, so a reader never
//! sees a half-written file.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// One named array attached to points or cells. `values.len() == components * n`.
#[derive(Debug, Clone, Copy)]
pub struct DataArray<'a> {
    /// Array name shown in ParaView.
    pub name: &'a str,
    /// Number of components per tuple (1 = scalar, 3 = vector, ...).
    pub components: usize,
    /// Tuple-major values: `values[i * components + c]`.
    pub values: &'a [f64],
    /// Written as `Int64` (whole numbers such as particle ids, exact up to 2^53), else as
    /// `Float64`.
    pub integer: bool,
}

/// VTK cell type ids used here.
const VTK_VERTEX: u8 = 1;
const VTK_LINE: u8 = 3;
const VTK_TRIANGLE: u8 = 5;
const VTK_POLYGON: u8 = 7;
const VTK_QUAD: u8 = 9;

/// Write an UnstructuredGrid `.vtu` of isolated points (one VTK_VERTEX cell per point, type 1) with point data.
pub fn write_points_vtu(
    path: &Path,
    points: &[[f64; 3]],
    point_data: &[DataArray],
) -> io::Result<()> {
    let n = points.len();
    check_arrays(point_data, n, "point")?;
    let cells = Cells::Vertices(n);
    write_atomic(path, |w| write_vtu(w, points, &cells, point_data, &[]))
}

/// Write an UnstructuredGrid `.vtu` of polygons: `vertices` are the mesh points, `cells` lists each cell's vertex indices (2 = line segment, VTK_LINE type 3; 3 = triangle type 5; 4 = quad type 9; other counts = polygon type 7), `cell_data` one value tuple per cell.
///
/// A cell with a single index is written as a VTK_VERTEX (type 1); an empty
/// cell or an index past the end of `vertices` is rejected as `InvalidInput`.
pub fn write_cells_vtu(
    path: &Path,
    vertices: &[[f64; 3]],
    cells: &[Vec<u32>],
    cell_data: &[DataArray],
) -> io::Result<()> {
    for (i, cell) in cells.iter().enumerate() {
        if cell.is_empty() {
            return Err(invalid(format!("cell {i} has no vertex indices")));
        }
        if let Some(&bad) = cell.iter().find(|&&v| v as usize >= vertices.len()) {
            return Err(invalid(format!(
                "cell {i} refers to vertex {bad}, but there are only {} vertices",
                vertices.len()
            )));
        }
    }
    check_arrays(cell_data, cells.len(), "cell")?;
    let cells = Cells::List(cells);
    write_atomic(path, |w| write_vtu(w, vertices, &cells, &[], cell_data))
}

/// Write a `.pvtu` index of point pieces: `pieces` are `.vtu` files of isolated points (as
/// [`write_points_vtu`] writes them; names relative to `path`), each with the arrays named
/// in `point_data` (only their names, components and kinds are read here).
pub fn write_points_pvtu(
    path: &Path,
    pieces: &[String],
    point_data: &[DataArray],
) -> io::Result<()> {
    write_atomic(path, |w| {
        w.write_all(b"<?xml version=\"1.0\"?>\n")?;
        w.write_all(
            b"<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
        )?;
        w.write_all(b"  <PUnstructuredGrid GhostLevel=\"0\">\n    <PPointData>\n")?;
        for a in point_data {
            writeln!(
                w,
                "      <PDataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"/>",
                if a.integer { "Int64" } else { "Float64" },
                escape_xml(a.name),
                a.components
            )?;
        }
        w.write_all(b"    </PPointData>\n    <PPoints>\n")?;
        w.write_all(
            b"      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n",
        )?;
        w.write_all(b"    </PPoints>\n    <PCells>\n")?;
        w.write_all(b"      <PDataArray type=\"Int64\" Name=\"connectivity\"/>\n")?;
        w.write_all(b"      <PDataArray type=\"Int64\" Name=\"offsets\"/>\n")?;
        w.write_all(b"      <PDataArray type=\"UInt8\" Name=\"types\"/>\n")?;
        w.write_all(b"    </PCells>\n")?;
        for piece in pieces {
            writeln!(w, "    <Piece Source=\"{}\"/>", escape_xml(piece))?;
        }
        w.write_all(b"  </PUnstructuredGrid>\n</VTKFile>\n")
    })
}

/// A `.pvd` collection: a time series index of dataset files.
#[derive(Debug, Clone, Default)]
pub struct PvdCollection {
    /// Entries in push order: (time, part, relative file name).
    entries: Vec<(f64, u32, String)>,
}

impl PvdCollection {
    /// An empty collection.
    pub fn new() -> Self {
        Self::default()
    }

    /// Append a dataset `file` (relative to the `.pvd`) for `time` and `part`.
    pub fn push(&mut self, time: f64, part: u32, file: &str) {
        self.entries.push((time, part, file.to_owned()));
    }

    /// Write the complete collection to `path` (atomically, via `<path>.tmp`).
    ///
    /// A non-finite time is rejected as `InvalidInput`.
    pub fn write(&self, path: &Path) -> io::Result<()> {
        if let Some((t, _, f)) = self.entries.iter().find(|e| !e.0.is_finite()) {
            return Err(invalid(format!(
                "pvd entry \"{f}\" has non-finite time {t}"
            )));
        }
        write_atomic(path, |w| {
            w.write_all(b"<?xml version=\"1.0\"?>\n")?;
            w.write_all(
                b"<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n",
            )?;
            w.write_all(b"  <Collection>\n")?;
            for (time, part, file) in &self.entries {
                writeln!(
                    w,
                    "    <DataSet timestep=\"{}\" group=\"\" part=\"{part}\" file=\"{}\"/>",
                    fmt_f64(*time),
                    escape_xml(file)
                )?;
            }
            w.write_all(b"  </Collection>\n</VTKFile>\n")
        })
    }
}

/// Cell description for the shared `.vtu` writer.
enum Cells<'a> {
    /// `n` VTK_VERTEX cells, cell `i` holds point `i`.
    Vertices(usize),
    /// Explicit vertex index lists.
    List(&'a [Vec<u32>]),
}

impl Cells<'_> {
    fn count(&self) -> usize {
        match self {
            Cells::Vertices(n) => *n,
            Cells::List(c) => c.len(),
        }
    }

    fn connectivity_len(&self) -> usize {
        match self {
            Cells::Vertices(n) => *n,
            Cells::List(c) => c.iter().map(Vec::len).sum(),
        }
    }
}

/// Cell type for a cell with `n` vertices.
fn cell_type(n: usize) -> u8 {
    match n {
        1 => VTK_VERTEX,
        2 => VTK_LINE,
        3 => VTK_TRIANGLE,
        4 => VTK_QUAD,
        _ => VTK_POLYGON,
    }
}

/// Check that each array has `n` tuples; `what` is "point" or "cell".
fn check_arrays(arrays: &[DataArray], n: usize, what: &str) -> io::Result<()> {
    for a in arrays {
        if a.components == 0 {
            return Err(invalid(format!(
                "{what} data array \"{}\" has 0 components",
                a.name
            )));
        }
        if a.components.checked_mul(n) != Some(a.values.len()) {
            return Err(invalid(format!(
                "{what} data array \"{}\" has {} values, expected {} components x {n} {what}s",
                a.name,
                a.values.len(),
                a.components
            )));
        }
    }
    Ok(())
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// `<path>.tmp`, next to `path`.
fn tmp_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".tmp");
    PathBuf::from(s)
}

/// Write through a `BufWriter` into `<path>.tmp`, sync, then rename onto `path`.
fn write_atomic(
    path: &Path,
    body: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    let tmp = tmp_path(path);
    let result = (|| {
        let mut w = BufWriter::with_capacity(1 << 16, File::create(&tmp)?);
        body(&mut w)?;
        let file = w.into_inner().map_err(io::IntoInnerError::into_error)?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        // Best effort: do not leave a stale temporary behind.
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// One appended array: its XML attributes and its byte size.
struct ArrayHeader {
    attrs: String,
    bytes: u64,
}

/// Write a complete `.vtu` document.
fn write_vtu<W: Write>(
    w: &mut W,
    points: &[[f64; 3]],
    cells: &Cells,
    point_data: &[DataArray],
    cell_data: &[DataArray],
) -> io::Result<()> {
    let n_cells = cells.count();
    let conn_len = cells.connectivity_len() as u64;

    // Headers in the same order as the binary blocks follow in AppendedData.
    let named = |a: &DataArray| ArrayHeader {
        attrs: format!(
            "type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"",
            if a.integer { "Int64" } else { "Float64" },
            escape_xml(a.name),
            a.components
        ),
        bytes: 8 * a.values.len() as u64,
    };
    let pd: Vec<ArrayHeader> = point_data.iter().map(named).collect();
    let cd: Vec<ArrayHeader> = cell_data.iter().map(named).collect();
    let pts = ArrayHeader {
        attrs: "type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"".into(),
        bytes: 24 * points.len() as u64,
    };
    let conn = ArrayHeader {
        attrs: "type=\"Int64\" Name=\"connectivity\"".into(),
        bytes: 8 * conn_len,
    };
    let offs = ArrayHeader {
        attrs: "type=\"Int64\" Name=\"offsets\"".into(),
        bytes: 8 * n_cells as u64,
    };
    let types = ArrayHeader {
        attrs: "type=\"UInt8\" Name=\"types\"".into(),
        bytes: n_cells as u64,
    };

    let mut offset = 0u64;
    let mut tag = |w: &mut W, indent: &str, h: &ArrayHeader| -> io::Result<()> {
        writeln!(
            w,
            "{indent}<DataArray {} format=\"appended\" offset=\"{offset}\"/>",
            h.attrs
        )?;
        offset += 8 + h.bytes;
        Ok(())
    };

    w.write_all(b"<?xml version=\"1.0\"?>\n")?;
    w.write_all(
        b"<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    )?;
    w.write_all(b"  <UnstructuredGrid>\n")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{n_cells}\">",
        points.len()
    )?;
    w.write_all(b"      <PointData>\n")?;
    for h in &pd {
        tag(w, "        ", h)?;
    }
    w.write_all(b"      </PointData>\n      <CellData>\n")?;
    for h in &cd {
        tag(w, "        ", h)?;
    }
    w.write_all(b"      </CellData>\n      <Points>\n")?;
    tag(w, "        ", &pts)?;
    w.write_all(b"      </Points>\n      <Cells>\n")?;
    tag(w, "        ", &conn)?;
    tag(w, "        ", &offs)?;
    tag(w, "        ", &types)?;
    w.write_all(b"      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n")?;
    w.write_all(b"  <AppendedData encoding=\"raw\">\n   _")?;

    for (a, h) in point_data.iter().chain(cell_data).zip(pd.iter().chain(&cd)) {
        w.write_all(&h.bytes.to_le_bytes())?;
        if a.integer {
            for &v in a.values {
                w.write_all(&(v as i64).to_le_bytes())?;
            }
        } else {
            write_f64s(w, a.values)?;
        }
    }
    w.write_all(&pts.bytes.to_le_bytes())?;
    for p in points {
        write_f64s(w, p)?;
    }

    w.write_all(&conn.bytes.to_le_bytes())?;
    match cells {
        Cells::Vertices(n) => (0..*n as u64).try_for_each(|i| w.write_all(&i.to_le_bytes()))?,
        Cells::List(list) => {
            for &v in list.iter().flatten() {
                w.write_all(&i64::from(v).to_le_bytes())?;
            }
        }
    }

    w.write_all(&offs.bytes.to_le_bytes())?;
    match cells {
        Cells::Vertices(n) => (1..=*n as u64).try_for_each(|i| w.write_all(&i.to_le_bytes()))?,
        Cells::List(list) => {
            let mut end = 0u64;
            for c in list.iter() {
                end += c.len() as u64;
                w.write_all(&end.to_le_bytes())?;
            }
        }
    }

    w.write_all(&types.bytes.to_le_bytes())?;
    match cells {
        Cells::Vertices(n) => {
            let chunk = [VTK_VERTEX; 4096];
            let mut left = *n;
            while left > 0 {
                let k = left.min(chunk.len());
                w.write_all(&chunk[..k])?;
                left -= k;
            }
        }
        Cells::List(list) => {
            for c in list.iter() {
                w.write_all(&[cell_type(c.len())])?;
            }
        }
    }

    w.write_all(b"\n  </AppendedData>\n</VTKFile>\n")
}

/// Write values as little-endian f64.
fn write_f64s<W: Write>(w: &mut W, values: &[f64]) -> io::Result<()> {
    values
        .iter()
        .try_for_each(|v| w.write_all(&v.to_le_bytes()))
}

/// Shortest round-trip decimal text for a finite `f64`, with an exponent for
/// very large or small magnitudes.
fn fmt_f64(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || (1e-5..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Escape text for an XML attribute value. Characters XML 1.0 cannot carry
/// (most control characters) become U+FFFD.
fn escape_xml(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            c if (c as u32) < 0x20 || c == '\u{FFFE}' || c == '\u{FFFF}' => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh, empty folder for one test, removed when dropped.
    fn scratch(name: &str) -> tempfile::TempDir {
        let prefix = format!("bisph-vtk-{name}-");
        tempfile::Builder::new().prefix(&prefix).tempdir().unwrap()
    }

    fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
        hay.windows(needle.len()).position(|w| w == needle)
    }

    fn attr(tag: &str, key: &str) -> Option<String> {
        let pat = format!(" {key}=\"");
        let start = tag.find(&pat)? + pat.len();
        let end = start + tag[start..].find('"')?;
        Some(tag[start..end].to_string())
    }

    fn unescape(s: &str) -> String {
        s.replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&quot;", "\"")
            .replace("&apos;", "'")
            .replace("&#9;", "\t")
            .replace("&#10;", "\n")
            .replace("&#13;", "\r")
            .replace("&amp;", "&")
    }

    /// A decoded appended array.
    #[derive(Debug)]
    struct Arr {
        name: String,
        ty: String,
        components: usize,
        bytes: Vec<u8>,
    }

    impl Arr {
        fn f64s(&self) -> Vec<f64> {
            assert_eq!(self.ty, "Float64", "{}", self.name);
            self.bytes
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                .collect()
        }
        fn i64s(&self) -> Vec<i64> {
            assert_eq!(self.ty, "Int64", "{}", self.name);
            self.bytes
                .chunks_exact(8)
                .map(|c| i64::from_le_bytes(c.try_into().unwrap()))
                .collect()
        }
    }

    /// Tiny reader: header text, piece sizes and all appended arrays in tag order.
    fn read_vtu(path: &Path) -> (String, usize, usize, Vec<Arr>) {
        let data = std::fs::read(path).unwrap();
        let marker = b"<AppendedData encoding=\"raw\">";
        let m = find(&data, marker).expect("AppendedData marker");
        let base = m + find(&data[m..], b"_").unwrap() + 1;
        let header = std::str::from_utf8(&data[..m]).unwrap().to_string();
        assert!(header.contains("header_type=\"UInt64\""));
        assert!(header.contains("byte_order=\"LittleEndian\""));
        assert!(data.ends_with(b"</AppendedData>\n</VTKFile>\n"));
        let piece = &header[header.find("<Piece").unwrap()..];
        let np: usize = attr(piece, "NumberOfPoints").unwrap().parse().unwrap();
        let nc: usize = attr(piece, "NumberOfCells").unwrap().parse().unwrap();
        let mut arrays = Vec::new();
        let mut rest = header.as_str();
        let mut end_of_last = base;
        while let Some(i) = rest.find("<DataArray ") {
            let tag_end = i + rest[i..].find("/>").unwrap();
            let tag = &rest[i..tag_end];
            assert_eq!(attr(tag, "format").as_deref(), Some("appended"));
            let off: usize = attr(tag, "offset").unwrap().parse().unwrap();
            let at = base + off;
            assert_eq!(at, end_of_last, "arrays must be contiguous");
            let size = u64::from_le_bytes(data[at..at + 8].try_into().unwrap()) as usize;
            end_of_last = at + 8 + size;
            arrays.push(Arr {
                name: unescape(&attr(tag, "Name").unwrap()),
                ty: attr(tag, "type").unwrap(),
                components: attr(tag, "NumberOfComponents").map_or(1, |c| c.parse().unwrap()),
                bytes: data[at + 8..at + 8 + size].to_vec(),
            });
            rest = &rest[tag_end..];
        }
        assert_eq!(&data[end_of_last..], b"\n  </AppendedData>\n</VTKFile>\n");
        (header, np, nc, arrays)
    }

    fn same_bits(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
    }

    #[test]
    fn points_roundtrip_exact() {
        let scratch = scratch("points");
        let dir = scratch.path();
        let path = dir.join("p.vtu");
        let points = [[0.0, 1.0, 2.0], [-1.5, 1e-300, f64::MAX], [0.1, 0.2, 0.3]];
        let rho = [1000.0, 999.999_999_9, f64::NAN];
        let vel = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, -7.0, -0.0, 9.5];
        let pd = [
            DataArray {
                name: "rho",
                components: 1,
                values: &rho,
                integer: false,
            },
            DataArray {
                name: "v<&\"'>",
                components: 3,
                values: &vel,
                integer: false,
            },
            DataArray {
                name: "id",
                components: 1,
                values: &[7.0, 0.0, 9_007_199_254_740_992.0],
                integer: true,
            },
        ];
        write_points_vtu(&path, &points, &pd).unwrap();
        assert!(!tmp_path(&path).exists());

        let (header, np, nc, arrays) = read_vtu(&path);
        assert!(header.contains("Name=\"v&lt;&amp;&quot;&apos;&gt;\""));
        assert_eq!((np, nc), (3, 3));
        let names: Vec<_> = arrays.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "rho",
                "v<&\"'>",
                "id",
                "Points",
                "connectivity",
                "offsets",
                "types"
            ]
        );
        assert!(same_bits(&arrays[0].f64s(), &rho));
        assert_eq!(arrays[1].components, 3);
        assert!(same_bits(&arrays[1].f64s(), &vel));
        assert_eq!(arrays[2].i64s(), [7, 0, 1 << 53]);
        assert_eq!(arrays[3].components, 3);
        assert!(same_bits(&arrays[3].f64s(), points.as_flattened()));
        assert_eq!(arrays[4].i64s(), [0, 1, 2]);
        assert_eq!(arrays[5].i64s(), [1, 2, 3]);
        assert_eq!(arrays[6].ty, "UInt8");
        assert_eq!(arrays[6].bytes, [1, 1, 1]);

        // Overwriting an existing file works and leaves no temporary.
        write_points_vtu(&path, &points[..1], &[]).unwrap();
        let (_, np, nc, _) = read_vtu(&path);
        assert_eq!((np, nc), (1, 1));
        assert!(!tmp_path(&path).exists());
    }

    #[test]
    fn cells_roundtrip_exact() {
        let scratch = scratch("cells");
        let dir = scratch.path();
        let path = dir.join("c.vtu");
        let verts = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 1.5, 0.0],
        ];
        let cells = vec![
            vec![0, 1],
            vec![0, 1, 2],
            vec![0, 1, 2, 3],
            vec![0, 1, 2, 4, 3],
            vec![4],
        ];
        let p = [1.0, 2.0, 3.0, 4.0, 5.0];
        let f = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
        let cd = [
            DataArray {
                name: "p",
                components: 1,
                values: &p,
                integer: false,
            },
            DataArray {
                name: "force",
                components: 2,
                values: &f,
                integer: false,
            },
        ];
        write_cells_vtu(&path, &verts, &cells, &cd).unwrap();
        let (header, np, nc, arrays) = read_vtu(&path);
        assert!(header.contains("<PointData>\n      </PointData>"));
        assert_eq!((np, nc), (5, 5));
        let names: Vec<_> = arrays.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(
            names,
            ["p", "force", "Points", "connectivity", "offsets", "types"]
        );
        assert!(same_bits(&arrays[0].f64s(), &p));
        assert_eq!(arrays[1].components, 2);
        assert!(same_bits(&arrays[1].f64s(), &f));
        assert!(same_bits(&arrays[2].f64s(), verts.as_flattened()));
        assert_eq!(
            arrays[3].i64s(),
            [0, 1, 0, 1, 2, 0, 1, 2, 3, 0, 1, 2, 4, 3, 4]
        );
        assert_eq!(arrays[4].i64s(), [2, 5, 9, 14, 15]);
        assert_eq!(arrays[5].bytes, [3, 5, 9, 7, 1]);
    }

    #[test]
    fn empty_inputs_give_valid_files() {
        let scratch = scratch("empty");
        let dir = scratch.path();
        let a = dir.join("a.vtu");
        let b = dir.join("b.vtu");
        let pd = [DataArray {
            name: "rho",
            components: 1,
            values: &[],
            integer: false,
        }];
        write_points_vtu(&a, &[], &pd).unwrap();
        write_cells_vtu(&b, &[], &[], &pd).unwrap();
        for path in [&a, &b] {
            let (_, np, nc, arrays) = read_vtu(path);
            assert_eq!((np, nc), (0, 0));
            assert_eq!(arrays.len(), 5);
            assert!(arrays.iter().all(|a| a.bytes.is_empty()));
        }
        let pvd = dir.join("empty.pvd");
        PvdCollection::new().write(&pvd).unwrap();
        let text = std::fs::read_to_string(&pvd).unwrap();
        assert!(text.contains("<Collection>\n  </Collection>\n</VTKFile>"));
    }

    #[test]
    fn bad_inputs_are_invalid_input() {
        let scratch = scratch("bad");
        let dir = scratch.path();
        let path = dir.join("x.vtu");
        let pts = [[0.0; 3]; 2];
        let check = |r: io::Result<()>, needle: &str| {
            let e = r.unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
            assert!(e.to_string().contains(needle), "{e}");
        };
        let short = [DataArray {
            name: "density",
            components: 1,
            values: &[1.0],
            integer: false,
        }];
        check(write_points_vtu(&path, &pts, &short), "density");
        let zero = [DataArray {
            name: "nothing",
            components: 0,
            values: &[],
            integer: false,
        }];
        check(write_points_vtu(&path, &pts, &zero), "nothing");
        let huge = [DataArray {
            name: "huge",
            components: usize::MAX,
            values: &[1.0],
            integer: false,
        }];
        check(write_points_vtu(&path, &pts, &huge), "huge");
        check(write_cells_vtu(&path, &pts, &[vec![0, 2]], &[]), "vertex 2");
        check(write_cells_vtu(&path, &pts, &[vec![]], &[]), "cell 0");
        let cd = [DataArray {
            name: "pressure",
            components: 1,
            values: &[1.0, 2.0],
            integer: false,
        }];
        check(write_cells_vtu(&path, &pts, &[vec![0, 1]], &cd), "pressure");
        let mut pvd = PvdCollection::new();
        pvd.push(f64::NAN, 0, "nan.vtu");
        check(pvd.write(&dir.join("x.pvd")), "nan.vtu");
        assert!(!path.exists() && !tmp_path(&path).exists());
        // A missing directory is an ordinary I/O error, not a panic.
        let missing = dir.join("no/such/dir/x.vtu");
        assert!(write_points_vtu(&missing, &pts, &[]).is_err());
    }

    #[test]
    fn pvd_lists_entries_in_order() {
        let scratch = scratch("pvd");
        let dir = scratch.path();
        let path = dir.join("series.pvd");
        let mut pvd = PvdCollection::new();
        pvd.push(0.0, 0, "fluid_0000.vtu");
        pvd.push(0.0, 1, "walls_0000.vtu");
        pvd.push(0.1, 0, "fluid_0001.vtu");
        pvd.push(1e-9, 0, "a&b <c>.vtu");
        pvd.push(2.5e20, 3, "late.vtu");
        pvd.write(&path).unwrap();
        assert!(!tmp_path(&path).exists());
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\""));
        assert!(text.ends_with("</Collection>\n</VTKFile>\n"));
        let got: Vec<(f64, u32, String)> = text
            .lines()
            .filter(|l| l.trim_start().starts_with("<DataSet "))
            .map(|l| {
                (
                    attr(l, "timestep").unwrap().parse().unwrap(),
                    attr(l, "part").unwrap().parse().unwrap(),
                    unescape(&attr(l, "file").unwrap()),
                )
            })
            .collect();
        let want = vec![
            (0.0, 0, "fluid_0000.vtu".to_string()),
            (0.0, 1, "walls_0000.vtu".to_string()),
            (0.1, 0, "fluid_0001.vtu".to_string()),
            (1e-9, 0, "a&b <c>.vtu".to_string()),
            (2.5e20, 3, "late.vtu".to_string()),
        ];
        assert_eq!(got, want);
    }

    #[test]
    fn escape_covers_xml_specials() {
        assert_eq!(escape_xml("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&apos;");
        assert_eq!(escape_xml("x\u{1}y\tz"), "x\u{FFFD}y&#9;z");
        assert_eq!(fmt_f64(0.1), "0.1");
        assert_eq!(fmt_f64(1e-9), "1e-9");
        assert_eq!(fmt_f64(-2.5e20), "-2.5e20");
    }
}
