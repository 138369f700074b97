#!/usr/bin/env bash
# The pictures of the add-on's panels in docs/images, made in Blender 3.4.1's real window
# under Xvfb (scripts/panel_screenshots.py): the classic add-on built by that Blender, the
# audit's test library (tests/blender/audit_library.py), Audit All Materials, and the
# Shader Editor's sidebar and Properties showing glossy-ggx-r1. Needs Debian's `blender`
# (3.4) and `xvfb`; run from anywhere, with gloffuse built (cargo build).
set -euo pipefail
cd "$(dirname "$0")/.."
blender="${GLOFFUSE_TEST_BLENDER_34:-/usr/bin/blender}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
./target/debug/gloffuse generate --addon "$work/addon.zip" --blender "$blender" \
    --mode multiscatter,layered,anisotropic,glass --no-provision
"$blender" -b --factory-startup -noaudio --python-exit-code 1 \
    --python tests/blender/audit_library.py -- --out "$work/library" >/dev/null
TMPDIR="$work" xvfb-run -a -s "-screen 0 1600x1000x24" "$blender" --factory-startup -noaudio \
    --enable-event-simulate "$work/library/rules.blend" --python scripts/panel_screenshots.py -- \
    --addon "$work/addon.zip" --user-resources "$work/user" --material glossy-ggx-r1 \
    --out "$work/shots"
mkdir -p docs/images
cp "$work/shots/shader-editor.png" docs/images/panel-shader-editor-3.4.png
cp "$work/shots/properties.png" docs/images/panel-properties-3.4.png
echo "wrote docs/images/panel-shader-editor-3.4.png, docs/images/panel-properties-3.4.png"
