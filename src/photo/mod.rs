//! Photo decoding (JPEG, PNG, TIFF, camera raw), EXIF facts and linearisation to linear light.
