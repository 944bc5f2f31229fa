//! Reading a body model from SMPL's keys, whether the file is an npz (dense arrays) or a
//! pickle (chumpy `Ch` arrays, a scipy CSC `J_regressor`), read by desal-io's npz reader and
//! restricted unpickler. Every key is checked for type, shape, finiteness and index range
//! before the model is built; keys the model does not use are kept as they came.

use std::path::Path;

use std::cell::RefCell;

use desal_io::npz::{AnyArray, AnyData, Dtype, NpzEntry, decode_npy_any};
use desal_io::pickle::{PyValue, unpickle};
use desal_mesh::Vec3;

use crate::error::BodyModelError;
use crate::model::{BodyModel, ExtraEntry, FileLayout, ModelKind, SparseRows};

/// The keys [`BodyModel`] holds in its own fields; every other key becomes an
/// [`ExtraEntry`] (the mean hand poses `hands_mean`, `hands_meanl`, `hands_meanr` are
/// also read into [`BodyModel::pose_mean`]).
pub const MODEL_KEYS: [&str; 7] =
    ["v_template", "f", "shapedirs", "posedirs", "weights", "kintree_table", "J_regressor"];

/// In a SMPL-X or FLAME file, `shapedirs` holds this many shape components before the
/// expression ones when it is wider (SMPL-X 1.1, FLAME 2020 and 2023: 300 + 100).
pub const SHAPE_SPACE: usize = 300;
/// SMPL-X 1.0's `shapedirs` has 20 columns: 10 shape, then 10 expression.
const SMPLX_V1_COLUMNS: usize = 20;

impl BodyModel {
    /// Reads the model at `path`: `.npz` or `.pkl` by extension, through desal-io's
    /// regular-file reader (a FIFO or folder is refused before it is opened).
    pub fn read(path: &Path) -> Result<Self, BodyModelError> {
        let bytes = desal_io::file::read_regular_file(path)?;
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("pkl") => Self::from_pkl_bytes(path, &bytes),
            _ => Self::from_npz_bytes(path, &bytes),
        }
    }

    /// A model from npz content `bytes` (stored entries, as `np.savez` writes); `path`
    /// names the file in messages.
    pub fn from_npz_bytes(path: &Path, bytes: &[u8]) -> Result<Self, BodyModelError> {
        let entries = desal_io::npz::read_npz_entries_from(path, bytes)?;
        build(path, Source::Npz(entries))
    }

    /// A model from pickle content `bytes` (the SMPL-family `.pkl`, Python 2 or 3, read by
    /// desal-io's restricted unpickler, which never runs pickled code); `path` names the
    /// file in messages.
    pub fn from_pkl_bytes(path: &Path, bytes: &[u8]) -> Result<Self, BodyModelError> {
        let value = unpickle(bytes).map_err(|reason| bad(path, "<pickle>", reason))?;
        let PyValue::Dict(items) = value else {
            return Err(bad(
                path,
                "<pickle>",
                format!("holds a {}, not a dict of arrays", value.type_name()),
            ));
        };
        // A later equal key replaces an earlier one, as in a Python dict (in linear time:
        // a hostile file may hold millions of keys).
        let mut entries: Vec<(String, PyValue)> = Vec::with_capacity(items.len());
        let mut slot_of: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
        for (key, value) in items {
            let PyValue::Str(key) = key else {
                return Err(bad(path, "<pickle>", format!("has a {} key, not a string", key.type_name())));
            };
            match slot_of.get(&key) {
                Some(&slot) => entries[slot].1 = value,
                None => {
                    slot_of.insert(key.clone(), entries.len());
                    entries.push((key, value));
                }
            }
        }
        build(path, Source::Pkl(entries))
    }
}

fn bad(path: &Path, key: &str, reason: impl Into<String>) -> BodyModelError {
    BodyModelError::BadKey { path: path.to_owned(), key: key.to_owned(), reason: reason.into() }
}

/// The file's keys, as stored.
enum Source {
    Npz(Vec<NpzEntry>),
    Pkl(Vec<(String, PyValue)>),
}

/// A key's matrix: dense, or a scipy CSC matrix (pickles' `J_regressor`).
enum Matrix {
    Dense(AnyArray),
    Csc { shape: [usize; 2], data: Vec<f64>, indices: Vec<i64>, indptr: Vec<i64> },
}

struct Reader<'a> {
    path: &'a Path,
    source: Source,
    /// The element type of every array read, by key (for [`FileLayout::dtypes`]).
    dtypes: RefCell<Vec<(String, Dtype)>>,
}

impl Reader<'_> {
    fn record_dtype(&self, key: &str, dtype: Option<Dtype>) {
        if let Some(dtype) = dtype {
            self.dtypes.borrow_mut().push((key.to_owned(), dtype));
        }
    }

    fn bad(&self, key: &str, reason: impl Into<String>) -> BodyModelError {
        bad(self.path, key, reason)
    }

    /// The matrix under `key`, `None` when the file has no such key.
    fn matrix(&self, key: &str) -> Result<Option<Matrix>, BodyModelError> {
        match &self.source {
            Source::Npz(entries) => match entries.iter().find(|e| e.name == key) {
                Some(entry) => {
                    Ok(Some(Matrix::Dense(decode_npy_any(&entry.npy).map_err(|e| self.bad(key, e))?)))
                }
                None => Ok(None),
            },
            Source::Pkl(entries) => match entries.iter().find(|(k, _)| k == key) {
                Some((_, value)) => self.pickled_matrix(key, value).map(Some),
                None => Ok(None),
            },
        }
    }

    /// A pickled array: an ndarray, a chumpy object holding one (`x`, or `a` gathered at
    /// `idxs` as `chumpy.reordering` keeps it), or a scipy CSC matrix.
    fn pickled_matrix(&self, key: &str, value: &PyValue) -> Result<Matrix, BodyModelError> {
        let PyValue::Object { class, state: Some(state), .. } = value else {
            return match value {
                PyValue::Array(a) => Ok(Matrix::Dense(a.clone())),
                other => Err(self.bad(key, format!("is a {}, not an array", other.type_name()))),
            };
        };
        if class.starts_with("scipy.sparse") {
            let array = |name: &str| match state.get(name) {
                Some(PyValue::Array(a)) => Ok(a),
                _ => Err(self.bad(key, format!("is a CSC matrix without its '{name}' array"))),
            };
            let shape = match state.get("_shape").or_else(|| state.get("shape")) {
                Some(PyValue::Tuple(dims)) => match dims.as_slice() {
                    [PyValue::Int(r), PyValue::Int(c)] if *r >= 0 && *c >= 0 => [*r as usize, *c as usize],
                    _ => return Err(self.bad(key, "is a CSC matrix with a bad shape")),
                },
                _ => return Err(self.bad(key, "is a CSC matrix without its shape")),
            };
            let data = array("data")?;
            self.record_dtype(key, data.data.dtype());
            let data = data.data.to_f64().ok_or_else(|| self.bad(key, "has non-numeric CSC data"))?;
            let indices = array("indices")?
                .data
                .to_i64()
                .ok_or_else(|| self.bad(key, "has non-integer CSC indices"))?;
            let indptr =
                array("indptr")?.data.to_i64().ok_or_else(|| self.bad(key, "has non-integer CSC indptr"))?;
            return Ok(Matrix::Csc { shape, data, indices, indptr });
        }
        if let Some(x) = state.get("x") {
            return self.pickled_matrix(key, x);
        }
        if let (Some(source), Some(PyValue::Array(idxs))) = (state.get("a"), state.get("idxs")) {
            let Matrix::Dense(source) = self.pickled_matrix(key, source)? else {
                return Err(self.bad(key, "indexes a sparse matrix"));
            };
            let values = source.data.to_f64().ok_or_else(|| self.bad(key, "indexes a non-numeric array"))?;
            let idxs = idxs.data.to_i64().ok_or_else(|| self.bad(key, "has non-integer 'idxs'"))?;
            let gathered = idxs
                .iter()
                .map(|&i| usize::try_from(i).ok().and_then(|i| values.get(i).copied()))
                .collect::<Option<Vec<f64>>>()
                .ok_or_else(|| self.bad(key, "has an index past its source array"))?;
            let shape = match state.get("preferred_shape") {
                Some(PyValue::Tuple(dims)) => dims
                    .iter()
                    .map(|d| match d {
                        PyValue::Int(n) => usize::try_from(*n).ok(),
                        _ => None,
                    })
                    .collect::<Option<Vec<_>>>()
                    .ok_or_else(|| self.bad(key, "has a bad 'preferred_shape'"))?,
                _ => vec![gathered.len()],
            };
            if shape.iter().product::<usize>() != gathered.len() {
                return Err(self.bad(key, "has a 'preferred_shape' that does not hold its values"));
            }
            return Ok(Matrix::Dense(AnyArray { shape, data: AnyData::F64(gathered) }));
        }
        Err(self.bad(key, format!("is a {class} holding no array ('x', or 'a' and 'idxs')")))
    }

    fn required(&self, key: &str) -> Result<Matrix, BodyModelError> {
        self.matrix(key)?.ok_or_else(|| self.bad(key, "is missing"))
    }

    /// A dense numeric array under `key` as f64, with its shape; every value finite.
    fn dense(&self, key: &str) -> Result<(Vec<usize>, Vec<f64>), BodyModelError> {
        match self.required(key)? {
            Matrix::Dense(a) => self.finite(key, a),
            Matrix::Csc { .. } => Err(self.bad(key, "is a sparse matrix, a dense array is needed")),
        }
    }

    fn finite(&self, key: &str, a: AnyArray) -> Result<(Vec<usize>, Vec<f64>), BodyModelError> {
        self.record_dtype(key, a.data.dtype());
        let values = a
            .data
            .to_f64()
            .ok_or_else(|| self.bad(key, format!("holds {}, not numbers", a.data.type_name())))?;
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(self.bad(key, format!("value {i} is not finite")));
        }
        Ok((a.shape, values))
    }

    fn expect_shape(
        &self,
        key: &str,
        shape: &[usize],
        expected: &[Option<usize>],
    ) -> Result<(), BodyModelError> {
        let fits = shape.len() == expected.len()
            && shape.iter().zip(expected).all(|(s, e)| e.is_none_or(|e| e == *s));
        if fits {
            return Ok(());
        }
        let wanted: Vec<String> = expected.iter().map(|e| e.map_or("_".into(), |n| n.to_string())).collect();
        Err(self.bad(key, format!("has shape {shape:?}, not ({})", wanted.join(", "))))
    }
}

fn build(path: &Path, source: Source) -> Result<BodyModel, BodyModelError> {
    let keys: Vec<String> = match &source {
        Source::Npz(entries) => entries.iter().map(|e| e.name.clone()).collect(),
        Source::Pkl(entries) => entries.iter().map(|(k, _)| k.clone()).collect(),
    };
    let r = Reader { path, source, dtypes: RefCell::new(Vec::new()) };

    // The tree first: its joint count names the kind.
    let kintree_table = match r.required("kintree_table")? {
        Matrix::Dense(a) => a,
        Matrix::Csc { .. } => {
            return Err(r.bad("kintree_table", "is a sparse matrix, a dense array is needed"));
        }
    };
    let (shape, table) = r.finite("kintree_table", kintree_table.clone())?;
    r.expect_shape("kintree_table", &shape, &[Some(2), None])?;
    let joint_count = shape[1];
    let kind = ModelKind::from_joint_count(joint_count)
        .ok_or(BodyModelError::UnknownKind { path: path.to_owned(), joints: joint_count })?;
    let mut parents = vec![None];
    for (joint, &parent) in table[..joint_count].iter().enumerate().skip(1) {
        let p = parent as i64;
        if parent != p as f64 || p < 0 || p as usize >= joint {
            return Err(BodyModelError::BadParent { path: path.to_owned(), joint, parent: p });
        }
        parents.push(Some(p as usize));
    }

    let (shape, values) = r.dense("v_template")?;
    r.expect_shape("v_template", &shape, &[None, Some(3)])?;
    let vertex_count = shape[0];
    let v_template: Vec<Vec3> = values.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();

    let (shape, values) = r.dense("f")?;
    r.expect_shape("f", &shape, &[None, Some(3)])?;
    if let Some(i) = values.iter().position(|&v| v < 0.0 || v >= vertex_count as f64 || v.fract() != 0.0) {
        return Err(
            r.bad("f", format!("corner {i} is {}, not a vertex index below {vertex_count}", values[i]))
        );
    }
    let faces = values.chunks_exact(3).map(|c| [c[0] as u32, c[1] as u32, c[2] as u32]).collect();

    // MANO files may store shapedirs flattened; SMPL's layout is (V, 3, S).
    let (mut shape, dirs) = r.dense("shapedirs")?;
    let shapedirs_flat = shape.len() == 1 && vertex_count > 0 && shape[0] % (3 * vertex_count) == 0;
    if shapedirs_flat {
        shape = vec![vertex_count, 3, shape[0] / (3 * vertex_count)];
    }
    r.expect_shape("shapedirs", &shape, &[Some(vertex_count), Some(3), None])?;
    let columns = shape[2];
    let shape_count = match (kind.has_expressions(), columns) {
        (true, c) if c > SHAPE_SPACE => SHAPE_SPACE,
        (true, SMPLX_V1_COLUMNS) if kind == ModelKind::SmplX => SMPLX_V1_COLUMNS / 2,
        (_, c) => c,
    };
    let (shapedirs, exprdirs) = split_columns(&dirs, columns, shape_count);

    let pose_features = 9 * (joint_count - 1);
    let (shape, posedirs) = r.dense("posedirs")?;
    r.expect_shape("posedirs", &shape, &[Some(vertex_count), Some(3), Some(pose_features)])?;

    let (shape, weights) = r.dense("weights")?;
    r.expect_shape("weights", &shape, &[Some(vertex_count), Some(joint_count)])?;
    let weights = SparseRows::from_dense(&weights, vertex_count, joint_count);

    let joint_regressor = match r.required("J_regressor")? {
        Matrix::Dense(a) => {
            let (shape, values) = r.finite("J_regressor", a)?;
            r.expect_shape("J_regressor", &shape, &[Some(joint_count), Some(vertex_count)])?;
            SparseRows::from_dense(&values, joint_count, vertex_count)
        }
        Matrix::Csc { shape, data, indices, indptr } => {
            if shape != [joint_count, vertex_count] {
                return Err(r.bad(
                    "J_regressor",
                    format!("has shape {shape:?}, not ({joint_count}, {vertex_count})"),
                ));
            }
            csc_to_rows(&data, &indices, &indptr, shape).map_err(|e| r.bad("J_regressor", e))?
        }
    };

    let mut pose_mean = vec![Vec3::zeros(); joint_count];
    for (key, first_joint) in hand_mean_keys(kind) {
        if let Some(m) = r.matrix(key)? {
            let Matrix::Dense(a) = m else { return Err(r.bad(key, "is a sparse matrix")) };
            let (_, values) = r.finite(key, a)?;
            if values.len() != 45 {
                return Err(r.bad(key, format!("holds {} values, not 45 (15 joints × 3)", values.len())));
            }
            for (k, c) in values.chunks_exact(3).enumerate() {
                pose_mean[first_joint + k] = Vec3::new(c[0], c[1], c[2]);
            }
        }
    }

    let extras = match r.source {
        Source::Npz(entries) => entries
            .into_iter()
            .filter(|e| !MODEL_KEYS.contains(&e.name.as_str()))
            .map(|e| (e.name, ExtraEntry::Npy(e.npy)))
            .collect(),
        Source::Pkl(entries) => entries
            .into_iter()
            .filter(|(k, _)| !MODEL_KEYS.contains(&k.as_str()))
            .map(|(k, v)| match v {
                PyValue::Array(a) => (k, ExtraEntry::Array(a)),
                other => (k, ExtraEntry::Pickled(other)),
            })
            .collect(),
    };

    let mut dtypes = r.dtypes.take();
    dtypes.retain(|(k, _)| MODEL_KEYS.contains(&k.as_str()));
    let layout = FileLayout { keys, dtypes, shapedirs_flat, kintree_table: Some(kintree_table) };

    Ok(BodyModel {
        kind,
        v_template,
        faces,
        shape_count,
        shapedirs,
        expression_count: columns - shape_count,
        exprdirs,
        posedirs,
        weights,
        parents,
        joint_regressor,
        pose_mean,
        extras,
        layout,
    })
}

/// `(V·3, columns)` row-major split into its first `left` columns and the rest.
fn split_columns(dirs: &[f64], columns: usize, left: usize) -> (Vec<f64>, Vec<f64>) {
    if columns == 0 {
        return (Vec::new(), Vec::new());
    }
    let mut a = Vec::with_capacity(dirs.len() / columns * left);
    let mut b = Vec::with_capacity(dirs.len() / columns * (columns - left));
    for row in dirs.chunks_exact(columns) {
        a.extend_from_slice(&row[..left]);
        b.extend_from_slice(&row[left..]);
    }
    (a, b)
}

/// A scipy CSC matrix (`indptr` per column into `indices`, the rows) as sparse rows,
/// checking every pointer and index.
fn csc_to_rows(
    data: &[f64],
    indices: &[i64],
    indptr: &[i64],
    shape: [usize; 2],
) -> Result<SparseRows, String> {
    let [rows, cols] = shape;
    if indptr.len() != cols + 1 || indices.len() != data.len() {
        return Err(format!(
            "is a CSC matrix with {} pointers for {cols} columns and {} indices for {} values",
            indptr.len(),
            indices.len(),
            data.len()
        ));
    }
    let mut triples: Vec<(usize, u32, f64)> = Vec::with_capacity(data.len());
    for col in 0..cols {
        let (start, end) = (indptr[col], indptr[col + 1]);
        if start < 0 || end < start || end as usize > data.len() {
            return Err(format!("is a CSC matrix whose column {col} points outside its data"));
        }
        for k in start as usize..end as usize {
            let row = usize::try_from(indices[k]).ok().filter(|&r| r < rows);
            let row =
                row.ok_or_else(|| format!("is a CSC matrix with row index {} past {rows}", indices[k]))?;
            if !data[k].is_finite() {
                return Err(format!("value at row {row}, column {col} is not finite"));
            }
            triples.push((row, col as u32, data[k]));
        }
    }
    triples.sort_by_key(|&(r, c, _)| (r, c));
    let mut out = SparseRows { offsets: vec![0; rows + 1], cols: Vec::new(), values: Vec::new() };
    for &(r, c, v) in &triples {
        out.offsets[r + 1] += 1;
        out.cols.push(c);
        out.values.push(v);
    }
    for r in 0..rows {
        out.offsets[r + 1] += out.offsets[r];
    }
    Ok(out)
}

/// Where each kind keeps its mean hand pose: key and first joint of its 15.
fn hand_mean_keys(kind: ModelKind) -> Vec<(&'static str, usize)> {
    match kind {
        ModelKind::SmplH => vec![("hands_meanl", 22), ("hands_meanr", 37)],
        ModelKind::SmplX => vec![("hands_meanl", 25), ("hands_meanr", 40)],
        ModelKind::Mano => vec![("hands_mean", 1)],
        _ => Vec::new(),
    }
}

/// A pickled value that numpy can hold without pickling, as an array: an ndarray, a
/// chumpy object's array, a scipy CSC matrix made dense, or a scalar string, bytes or
/// number as a 0-d array (what `np.savez` makes of them). `Err` names what it is instead
/// (a dict, a list, None): such a value has no plain `.npy` form.
pub(crate) fn pickled_array(value: &PyValue) -> Result<AnyArray, String> {
    let scalar = |data: AnyData| Ok(AnyArray { shape: Vec::new(), data });
    match value {
        PyValue::Str(s) => scalar(AnyData::Unicode(vec![s.clone()])),
        PyValue::Bytes(b) => scalar(AnyData::Bytes(vec![b.clone()])),
        PyValue::Int(n) => scalar(AnyData::I64(vec![*n])),
        PyValue::Float(x) => scalar(AnyData::F64(vec![*x])),
        PyValue::Bool(b) => scalar(AnyData::Bool(vec![*b])),
        PyValue::Array(a) => Ok(a.clone()),
        PyValue::Object { .. } => {
            let path = Path::new("<pickle>");
            let reader = Reader { path, source: Source::Pkl(Vec::new()), dtypes: RefCell::new(Vec::new()) };
            match reader.pickled_matrix("value", value).map_err(|e| e.to_string())? {
                Matrix::Dense(a) => Ok(a),
                Matrix::Csc { shape, data, indices, indptr } => {
                    let rows = csc_to_rows(&data, &indices, &indptr, shape)?;
                    let dense = rows.to_dense(shape[0], shape[1]);
                    Ok(AnyArray { shape: shape.to_vec(), data: AnyData::F64(dense) })
                }
            }
        }
        other => Err(format!("is a {}, which has no plain numpy form", other.type_name())),
    }
}
