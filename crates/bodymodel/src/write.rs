//! Writing a model as an npz in its file's own form: SMPL's keys and every extra in the
//! file's key order, each of SMPL's arrays in the element type the file stored it in
//! ([`crate::model::FileLayout`]), `kintree_table` exactly as it came. A model read from a
//! `.pkl` is written as an npz of the same keys: chumpy arrays as their arrays, scipy
//! matrices dense, strings and numbers as 0-d arrays; a value with no plain numpy form (a
//! dict such as SMPL 1.0's `pose_training_info`) is left out and named in
//! [`NpzModel::dropped`]. The bytes are deterministic (desal-io's stored-entry archive).

use desal_io::npz::{AnyArray, AnyData, Dtype, NpzEntry, encode_npy_any, encode_npz_entries};

use crate::error::BodyModelError;
use crate::model::{BodyModel, ExtraEntry};
use crate::read::MODEL_KEYS;

/// A model's npz bytes and the keys left out, each with why.
#[derive(Debug, Clone, PartialEq)]
pub struct NpzModel {
    pub bytes: Vec<u8>,
    pub dropped: Vec<(String, String)>,
}

impl BodyModel {
    /// The model as an npz (see the module docs): what body-models' and `smplx`'s loaders
    /// read, in the layout of the file the model came from.
    pub fn to_npz(&self) -> Result<NpzModel, BodyModelError> {
        // The file's order; SMPL's keys a code-built model has no file order for first.
        let mut keys: Vec<String> = self.layout.keys.clone();
        for key in MODEL_KEYS.iter().map(|k| k.to_string()).chain(self.extras.iter().map(|(k, _)| k.clone()))
        {
            if !keys.contains(&key) {
                keys.push(key);
            }
        }
        let mut entries = Vec::with_capacity(keys.len());
        let mut dropped = Vec::new();
        for key in keys {
            let npy = if MODEL_KEYS.contains(&key.as_str()) {
                encode(&key, &self.model_array(&key))?
            } else {
                match self.extras.iter().find(|(k, _)| *k == key).map(|(_, e)| e) {
                    // A key of the layout the model no longer holds (left out on purpose).
                    None => continue,
                    Some(ExtraEntry::Npy(bytes)) => bytes.clone(),
                    Some(ExtraEntry::Array(a)) => encode(&key, a)?,
                    Some(ExtraEntry::Pickled(value)) => match crate::read::pickled_array(value) {
                        Ok(a) => encode(&key, &a)?,
                        Err(why) => {
                            dropped.push((key, why));
                            continue;
                        }
                    },
                }
            };
            entries.push(NpzEntry { name: key, npy });
        }
        let bytes = encode_npz_entries(&entries).map_err(|reason| BodyModelError::Write { reason })?;
        Ok(NpzModel { bytes, dropped })
    }

    /// One of SMPL's keys as the file stored it.
    fn model_array(&self, key: &str) -> AnyArray {
        let (v, j) = (self.vertex_count(), self.joint_count());
        let typed = |shape: Vec<usize>, values: &[f64], default: Dtype| AnyArray {
            shape,
            data: AnyData::from_f64(self.layout.dtype(key).unwrap_or(default), values),
        };
        match key {
            "v_template" => {
                let values: Vec<f64> = self.v_template.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
                typed(vec![v, 3], &values, Dtype::F64)
            }
            "f" => {
                let values: Vec<f64> = self.faces.iter().flatten().map(|&c| f64::from(c)).collect();
                typed(vec![self.faces.len(), 3], &values, Dtype::I32)
            }
            "shapedirs" => {
                // The shape directions, then the expression ones, per (vertex, coordinate).
                let (s, e) = (self.shape_count, self.expression_count);
                let mut values = Vec::with_capacity(v * 3 * (s + e));
                for row in 0..v * 3 {
                    values.extend_from_slice(&self.shapedirs[row * s..(row + 1) * s]);
                    values.extend_from_slice(&self.exprdirs[row * e..(row + 1) * e]);
                }
                let shape = if self.layout.shapedirs_flat { vec![values.len()] } else { vec![v, 3, s + e] };
                typed(shape, &values, Dtype::F64)
            }
            "posedirs" => typed(vec![v, 3, self.pose_feature_count()], &self.posedirs, Dtype::F64),
            "weights" => typed(vec![v, j], &self.weights.to_dense(v, j), Dtype::F64),
            "J_regressor" => typed(vec![j, v], &self.joint_regressor.to_dense(j, v), Dtype::F64),
            "kintree_table" => self.layout.kintree_table.clone().unwrap_or_else(|| {
                let parents = self.parents.iter().map(|p| p.map_or(-1, |p| p as i64));
                AnyArray { shape: vec![2, j], data: AnyData::I64(parents.chain(0..j as i64).collect()) }
            }),
            other => unreachable!("'{other}' is not one of MODEL_KEYS"),
        }
    }
}

fn encode(key: &str, array: &AnyArray) -> Result<Vec<u8>, BodyModelError> {
    encode_npy_any(array).map_err(|e| BodyModelError::Write { reason: format!("'{key}': {e}") })
}
