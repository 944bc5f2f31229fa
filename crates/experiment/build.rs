//! Sets `cfg(desal_shared_data)` for the tests that need `../shared/datasets`.

fn main() {
    desal_shared_data::emit_cfg();
}
