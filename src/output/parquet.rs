//! Tables as Parquet (zstd): ensemble members and sweep cells, one row each, in files that
//! pandas, polars and Dask read alone or, one per shard or chunk in a directory, as one dataset.
//! The numbers are those of the CSV tables ([`super::table_csv`]); columns named in
//! `integers` are 64-bit integers, the rest doubles, an undefined value a null; every row also
//! carries the constants the table was made under (seed, model, tool version).

use std::sync::Arc;

use arrow_array::{ArrayRef, Float64Array, Int64Array, RecordBatch, StringArray, UInt64Array};
use arrow_schema::{DataType, Field, Schema};
use parquet::arrow::ArrowWriter;
use parquet::basic::{Compression, ZstdLevel};
use parquet::file::properties::WriterProperties;

/// A value repeated on every row of a table.
#[derive(Debug, Clone, PartialEq)]
pub enum Constant {
    /// Text, e.g. the model's name.
    Text(String),
    /// An unsigned integer, e.g. the seed.
    Unsigned(u64),
}

/// The tool's version, as every table records it.
pub const TOOL_VERSION: &str = env!("CARGO_PKG_VERSION");

/// The constants every table records where it came from: the seed of its draws (for an
/// ensemble's), the model and the tool's version.
pub fn provenance(model: crate::run::Model, seed: Option<u64>) -> Vec<(&'static str, Constant)> {
    let mut constants: Vec<(&'static str, Constant)> = seed.map(|s| ("seed", Constant::Unsigned(s))).into_iter().collect();
    constants.push(("model", Constant::Text(model.name().into())));
    constants.push(("version", Constant::Text(TOOL_VERSION.into())));
    constants
}

/// A Parquet file (zstd) of `rows` under `header`, then one column per constant.
pub fn table_parquet(
    header: &[String],
    rows: &[Vec<Option<f64>>],
    integers: &[&str],
    constants: &[(&str, Constant)],
) -> Result<Vec<u8>, parquet::errors::ParquetError> {
    let mut fields = Vec::with_capacity(header.len() + constants.len());
    let mut columns: Vec<ArrayRef> = Vec::with_capacity(fields.capacity());
    for (c, name) in header.iter().enumerate() {
        let values = rows.iter().map(|r| r.get(c).copied().flatten());
        if integers.contains(&name.as_str()) {
            fields.push(Field::new(name, DataType::Int64, true));
            columns.push(Arc::new(values.map(|x| x.map(|x| x as i64)).collect::<Int64Array>()));
        } else {
            fields.push(Field::new(name, DataType::Float64, true));
            columns.push(Arc::new(values.collect::<Float64Array>()));
        }
    }
    for (name, value) in constants {
        match value {
            Constant::Text(s) => {
                fields.push(Field::new(*name, DataType::Utf8, false));
                columns.push(Arc::new(StringArray::from(vec![s.as_str(); rows.len()])));
            }
            Constant::Unsigned(u) => {
                fields.push(Field::new(*name, DataType::UInt64, false));
                columns.push(Arc::new(UInt64Array::from(vec![*u; rows.len()])));
            }
        }
    }
    let batch = RecordBatch::try_new(Arc::new(Schema::new(fields)), columns)?;
    let props = WriterProperties::builder().set_compression(Compression::ZSTD(ZstdLevel::try_new(3)?)).build();
    let mut bytes = Vec::new();
    let mut writer = ArrowWriter::try_new(&mut bytes, batch.schema(), Some(props))?;
    writer.write(&batch)?;
    writer.close()?;
    Ok(bytes)
}
