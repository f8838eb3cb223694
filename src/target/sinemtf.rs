//! Reader for the MITRE sineMTF target format (`tgt.txt`): a serial number, the
//! patch count, the target's width and height in mm, then per patch a label, a
//! type letter (`d` density patch, `s` sine pattern) and its numbers. Text after
//! `#` is a comment.

use super::Target;

/// Parses a sineMTF target description into a [`Target`].
pub fn parse(_text: &str) -> Result<Target, String> {
    Err("sineMTF target files are not read yet".to_string())
}
