#!/usr/bin/env bash
# Installs the Debian packages livedrummer needs, only when one is missing.
# Runs as root (CI, stage rigs set up by a technician) or through sudo when available.
set -euo pipefail
# jackd2: MIDI through a real JACK server in tests; EGL + Mesa: headless rendering; libportaudio2:
# sounddevice (audio clock); xvfb + xauth: the window smoke test on a virtual screen;
# libfluidsynth3: pyfluidsynth (render --soundfont); libjack-jackd2-dev: the C reference client
# of `livedrummer bench input_load` (compiled for the run with cc); xdotool: keys pressed in the
# window test; chromium: the practice report test loads the HTML report in a headless browser;
# timgm6mb-soundfont: a real sampled General MIDI SoundFont, which the tests render with and
# from which the percussion recogniser's tests and `bench transcribe` make their audio;
# libsndfile1: soundfile (the samples of SFZ kits). fluid-soundfont-gm,
# musescore-general-soundfont-small, hydrogen-drumkits: more drum kits for the acoustic
# recogniser's multi-kit corpus (livedrummer acoustic train, bench transcribe
# --leave-one-kit-out; an absent kit is skipped with a line).
packages=(python3-venv jackd2 libegl1 libegl-mesa0 libgl1-mesa-dri libportaudio2 xvfb xauth libfluidsynth3 libjack-jackd2-dev xdotool chromium timgm6mb-soundfont libsndfile1 fluid-soundfont-gm musescore-general-soundfont-small hydrogen-drumkits)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
# python3 from pyenv or elsewhere already carries venv; only ask apt when it is really absent.
if python3 -c 'import venv, ensurepip' 2>/dev/null; then
  missing=("${missing[@]/python3-venv}")
fi
missing=(${missing[@]+"${missing[@]}"})
[ ${#missing[@]} -eq 0 ] && exit 0
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
$sudo apt-get update
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
