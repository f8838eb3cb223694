#!/bin/sh
# Regenerates the sample photos in testdata/ with `sweepmtf simulate`
# (each writes STEM.<ext>, STEM.truth.csv and STEM.json). Run from the
# repository root: sh testdata/regenerate.sh
set -e
S="${SWEEPMTF:-cargo run --release --quiet --} simulate"
OPT="--system targets/systems/aps_c_f4.toml"

# Log sweep, 8-bit sRGB JPEG at quality 90, mild shot and read noise (the README's main command).
$S --target demo:log $OPT --size 1200x800 --full-well 20000 --read-noise 4 --seed 1 \
   --jpeg 90 -o testdata/sweep_log_srgb_q90.jpg
# Linear sweep, 8-bit sRGB PNG, noiseless.
$S --target demo:linear $OPT --size 1200x800 -o testdata/sweep_linear_srgb.png
# Rotated 12° and tilted 25° about the vertical axis, 8-bit sRGB PNG, mild noise
# (4× oversampling: the far end of the sweep reaches 1.2 cy/px).
$S --target demo:log $OPT --size 1200x800 --rotate 12 --tilt 25,y --oversample 4 \
   --full-well 20000 --read-noise 4 --seed 2 -o testdata/sweep_log_rot12_tilt25.png
# 16-bit linear Bayer RGGB mosaic (TIFF with CFA tags), mild noise.
$S --target demo:log $OPT --size 900x600 --bayer RGGB --full-well 20000 --read-noise 4 \
   --seed 3 -o testdata/sweep_log_bayer_rggb.tif
# The README's main command: the shipped A4 log chart (targets/a4_log.toml, with
# fiducials) rotated 4°, tilted 15°, 20 % fall-off, noise, JPEG q90.
$S --target targets/a4_log.toml $OPT --gaussian sigma=2.5um --size 2000x1400 --rotate 4 \
   --tilt 15,y --falloff 0.2 --oversample 4 --full-well 20000 --read-noise 4 --seed 5 \
   --jpeg 90 -o testdata/a4_log_shot.jpg

# A small JPEG with restart markers every 43 MCUs (0x2B), written by
# libjpeg-turbo 2.1.5's cjpeg (Debian libjpeg-turbo-progs), for the scan-data
# check (src/photo/jpeg_check.rs): a 320×192 colour pattern.
python3 -c "
w,h=320,192
d=bytes(v for y in range(h) for x in range(w) for v in ((x*3)%256,(y*5)%256,((x^y)*7)%256))
open('/tmp/rst.ppm','wb').write(b'P6 %d %d 255\n'%(w,h)+d)"
cjpeg -quality 90 -restart 2B -outfile testdata/restart_markers_cjpeg.jpg /tmp/rst.ppm
