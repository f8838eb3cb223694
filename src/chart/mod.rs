//! Printable sine-sweep and sine-patch charts at true physical size (PNG, TIFF, PDF).
