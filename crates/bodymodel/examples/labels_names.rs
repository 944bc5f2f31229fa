//! Prints the parts `labels_from_weights` makes of the CC0 fixture (or a model file):
//! `cargo run -p desal-bodymodel --example labels_names -- [MODEL] [PARTS]`.

use desal_bodymodel::{BodyModel, labels_from_weights};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().filter(|a| a != "-");
    let parts: usize = args.next().map_or(Ok(16), |s| s.parse())?;
    let model = match path {
        Some(path) => BodyModel::read(std::path::Path::new(&path))?,
        None => {
            let assets = desal_sample::SourceAssets::load(&desal_sample::source::repository_source_dir())?;
            let npz = desal_sample::smpl_layout::smpl_layout_model(&assets)?.npz()?;
            BodyModel::from_npz_bytes(std::path::Path::new("fixture.npz"), &npz)?
        }
    };
    let labels = labels_from_weights(&model, parts);
    let mut sizes = vec![0usize; labels.part_count()];
    labels.labels.iter().for_each(|&p| sizes[p as usize] += 1);
    for (name, size) in labels.names.iter().zip(sizes) {
        println!("{name:>16} {size:>6} vertices");
    }
    Ok(())
}
