//! Finding the chart in a photo: fiducial detection and corner refinement.
