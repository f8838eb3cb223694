//! Camera simulator: renders a target through a modelled camera and writes the exact truth.
