//! Helpers shared by the integration tests, one module per job: independent oracles
//! (`oracle`), real Blenders (`blender`), and the binary itself ([`gloffuse`]).
#![allow(dead_code)]

pub mod blender;
pub mod oracle;

/// The `gloffuse` binary under test.
pub fn gloffuse() -> assert_cmd::Command {
    assert_cmd::Command::cargo_bin("gloffuse").expect("the gloffuse binary is built")
}
