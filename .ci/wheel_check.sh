#!/usr/bin/env bash
# The wheel, installed into a fresh venv outside the checkout, runs its commands with the bundled scenes.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
python="${PYTHON:-python3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
rm -rf "$repo/build"  # setuptools would put stale files of an earlier build into the wheel
"$python" -m pip wheel --quiet --no-deps --wheel-dir "$work/dist" "$repo"
wheel="$(ls "$work"/dist/ti_golf-*.whl)"
# The listing goes to a file first: `grep -q` stops reading at the first match, and under pipefail the
# writer's broken pipe would fail the check on a wheel that is fine.
"$python" -m zipfile -l "$wheel" > "$work/wheel.txt"
grep -q "ti_golf/scene/data/ball_pit.toml" "$work/wheel.txt" || { echo "wheel-check: no scenes in $wheel"; exit 1; }
grep -q "ti_golf/scene/data/studies/repose.toml" "$work/wheel.txt" || { echo "wheel-check: no studies in $wheel"; exit 1; }
"$python" -m venv "$work/venv"
"$work/venv/bin/pip" install --quiet "$wheel"
cd "$work"  # outside the checkout: nothing of it is importable from here
tg="$work/venv/bin/ti-golf"
"$tg" --version
"$tg" scenes > scenes.txt && grep -q "^golf_hole " scenes.txt
"$tg" schema --out scene.schema.json
"$tg" table
"$tg" run break_shot --steps 200 --out break_shot.npz
"$tg" run golf_hole --t 1
"$tg" render break_shot --steps 100 --size 320x240 --out break_shot.png
test -s break_shot.png
echo "wheel-check: $(basename "$wheel") installs and runs outside the checkout"
