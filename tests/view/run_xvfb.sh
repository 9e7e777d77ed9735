#!/usr/bin/env bash
# hapticfield_view in a real window under Xvfb: the window opens, runs for
# two seconds with the mouse probe held at 150,120 px, the X server's whole
# screen is grabbed (ImageMagick's import) and view_check finds the picture
# and the cursor at the probe's position in it. Then the same with a video
# from 0.5 s at 4x: the 3 s test clip ends after 0.625 s, so two seconds in
# the window must have followed it from frame 5 to the last frame, held (the
# frame of video time 2.95 s). Then a shape in the 3D view: a generated
# sphere (shape_check --make-sphere) seen head-on from 200 mm, the window
# grabbed, and shape_check finds the sphere's disc at the pinhole
# projection's radius with the proxy and HIP markers on it.
# Where xdotool is installed, the same sphere again after 35 wheel notches
# forward over its centre: the HIP goes 35 mm in, and the window must not
# zoom (Qt's default view grew 1.1 times a notch), so shape_check finds the
# disc at the same radius.
#   tests/view/run_xvfb.sh BUILD_DIR
set -euo pipefail
build=${1:?usage: run_xvfb.sh BUILD_DIR}
here=$(cd "$(dirname "$0")" && pwd)
picture="$here/../../examples/data/coffee.png"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$build/tests/view_check" --make-clip "$work/clip.avi"
"$build/tests/shape_check" --make-sphere "$work/sphere.obj"
xvfb-run -a -s "-screen 0 1280x1024x24" bash -c '
  "$1" "$2" --start 150,120 --seconds 3 --realtime off > "$3/view.log" 2>&1 &
  view=$!
  sleep 2
  import -window root "$3/screen.png"
  wait "$view"
  "$1" "$3/clip.avi" --from 0.5 --speed 4 --start 200,250 --seconds 3 --realtime off > "$3/video.log" 2>&1 &
  view=$!
  sleep 2
  import -window root "$3/video.png"
  wait "$view"
  "$1" --shape "$3/sphere.obj" --view 0,0 --distance 200 --seconds 3 --realtime off > "$3/shape.log" 2>&1 &
  view=$!
  sleep 2
  import -window root "$3/shape.png"
  wait "$view"' _ "$build/examples/hapticfield_view" "$picture" "$work"
cat "$work/view.log" "$work/video.log" "$work/shape.log"
"$build/tests/view_check" "$work/screen.png" "$picture" 150,120
"$build/tests/view_check" "$work/video.png" "$work/clip.avi" 200,250 2.95 2.95,2.95
"$build/tests/shape_check" "$work/shape.png" 40 200
if command -v xdotool > /dev/null; then
  xvfb-run -a -s "-screen 0 1280x1024x24" bash -c '
    "$1" --shape "$2/sphere.obj" --view 0,0 --distance 200 --seconds 4 --realtime off > "$2/wheel.log" 2>&1 &
    view=$!
    sleep 1.5
    window=$(xdotool search --sync --name "^hapticfield_view$" | head -n 1)
    xdotool mousemove --window "$window" 410 310 click --repeat 35 --delay 20 4
    sleep 1
    import -window root "$2/wheel.png"
    wait "$view"' _ "$build/examples/hapticfield_view" "$work"
  cat "$work/wheel.log"
  "$build/tests/shape_check" "$work/wheel.png" 40 200
else
  echo "run_xvfb.sh: xdotool is not installed; the wheel is not checked in a window"
fi
