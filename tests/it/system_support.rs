//! The camera systems the integration tests render through.

/// The f/4 APS-C system the shipped samples use (diffraction × square pixel).
pub fn aps_c_f4() -> sweepmtf::model::System {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("targets/systems/aps_c_f4.toml");
    sweepmtf::model::System::from_file(&p).unwrap()
}
