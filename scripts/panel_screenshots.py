"""The gloffuse add-on's panels in Blender 3.4's real window (not --background), under a
virtual X server, for the pictures in docs/images (scripts/panel-screenshots.sh runs it):
installs the classic add-on, makes MATERIAL active, runs gloffuse.audit_file as a user's
button would, opens the Shader Editor's sidebar on its Gloffuse tab and Properties on the
material, and takes screenshots once Blender has drawn both Gloffuse panels:

    xvfb-run -a -s "-screen 0 1600x1000x24" blender --factory-startup -noaudio \
        --enable-event-simulate FILE.blend --python panel_screenshots.py -- \
        --addon gloffuse-addon.zip --user-resources EMPTY_DIR --material NAME --out DIR

Writes DIR/window.png, DIR/shader-editor.png and DIR/properties.png and quits with 0;
any failure (a panel never drawn, a draw that raised) exits 1, a timeout 2. Not a test:
Blender 3.4.1 crashed (SIGSEGV) once in four runs on a loaded machine, after the
simulated Ctrl+Wheel that picks the sidebar's tab; run it again if it does.
"""
import argparse
import os
import sys
import threading
import traceback

TIMEOUT_S = 90


def options():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    for name in ("--addon", "--user-resources", "--material", "--out"):
        parser.add_argument(name, required=True)
    return parser.parse_args(argv)


OPTIONS = options()
# 3.4 reads these at each use: the add-on goes into a fresh user folder, not the user's.
for _kind in ("SCRIPTS", "DATAFILES", "CONFIG"):
    os.environ["BLENDER_USER_" + _kind] = os.path.join(OPTIONS.user_resources, _kind.lower())
os.makedirs(os.environ["BLENDER_USER_CONFIG"], exist_ok=True)

import bpy  # noqa: E402 -- after the environment it reads

DRAWN = {}  # panel class name -> how many times Blender drew it since the last clear


def die(code=1):
    # An exception inside a timer is only printed, and Blender would keep running.
    traceback.print_exc()
    sys.stdout.flush()
    os._exit(code)


def region(area, kind):
    return next(r for r in area.regions if r.type == kind)


def watch(panel_name):
    """Count the panel's draws (a draw callback runs after the panel's own draw, so a
    draw that raised is never counted)."""
    def mark(_panel, _context):
        DRAWN[panel_name] = DRAWN.get(panel_name, 0) + 1
    getattr(bpy.types, panel_name).append(mark)


def install_and_audit():
    bpy.ops.preferences.addon_install(filepath=os.path.abspath(OPTIONS.addon))
    bpy.ops.preferences.addon_enable(module="gloffuse")
    material = bpy.data.materials[OPTIONS.material]
    obj = next(o for o in bpy.data.objects if o.type == "MESH"
               and material in [slot.material for slot in o.material_slots])
    for other in bpy.context.view_layer.objects:
        other.select_set(other == obj)
    bpy.context.view_layer.objects.active = obj
    obj.active_material_index = [slot.material for slot in obj.material_slots].index(material)
    if bpy.ops.gloffuse.audit_file() != {"FINISHED"}:
        raise RuntimeError("gloffuse.audit_file did not finish")
    for name in ("GLOFFUSE_PT_material", "GLOFFUSE_PT_shader_editor", "GLOFFUSE_PT_all_materials"):
        watch(name)


def build_layout(window):
    """Generator: yields wherever Blender has to redraw before the next step can work."""
    screen = window.screen
    big = max((a for a in screen.areas if a.type != "PROPERTIES"),
              key=lambda a: (a.type == "VIEW_3D", a.width * a.height))
    with bpy.context.temp_override(window=window, screen=screen, area=big):
        # A wider right-hand column, so that Properties shows the panel's words.
        bpy.ops.screen.area_move(x=big.x + big.width, y=big.y + big.height // 2, delta=-200)
        before = set(screen.areas)
        bpy.ops.screen.area_split(direction="HORIZONTAL", factor=0.4)
    new = next(a for a in screen.areas if a not in before)
    yield  # a split-off area has no size until the next redraw
    editor = max((big, new), key=lambda a: a.height)
    editor.ui_type = "ShaderNodeTree"
    editor.spaces.active.show_region_ui = True
    props = next(a for a in screen.areas if a.type == "PROPERTIES")
    props.spaces.active.context = "MATERIAL"
    yield
    yield  # the node editor loads its tree, and resets its view, on its first redraws
    with bpy.context.temp_override(window=window, area=editor, region=region(editor, "WINDOW")):
        bpy.ops.node.view_all()
    # An add-on's panel comes after Blender's own: scroll Properties to the end.
    with bpy.context.temp_override(window=window, area=props, region=region(props, "WINDOW")):
        for _ in range(30):
            bpy.ops.view2d.scroll_down(page=True)
    return editor, props


def select_sidebar_tab(window, editor):
    """Generator: 3.4 has no API for a sidebar's active tab, so Ctrl+Wheel over the tab
    strip, as a user would, until Blender draws the Gloffuse tab's panel."""
    ui = region(editor, "UI")
    x, y = ui.x + ui.width - 4, ui.y + ui.height // 2  # the tab strip, no button there
    for _ in range(16):
        DRAWN.clear()
        yield
        if DRAWN.get("GLOFFUSE_PT_shader_editor"):
            return
        window.event_simulate("MOUSEMOVE", "NOTHING", x=x, y=y)
        window.event_simulate("WHEELDOWNMOUSE", "PRESS", x=x, y=y, ctrl=True)
    raise RuntimeError("the sidebar's Gloffuse tab never showed")


def steps(window):
    install_and_audit()
    editor, props = yield from build_layout(window)
    yield from select_sidebar_tab(window, editor)
    DRAWN.clear()
    yield
    yield
    missing = [name for name in ("GLOFFUSE_PT_material", "GLOFFUSE_PT_shader_editor",
                                 "GLOFFUSE_PT_all_materials") if not DRAWN.get(name)]
    if missing:
        raise RuntimeError("Blender did not draw %s" % ", ".join(missing))
    os.makedirs(OPTIONS.out, exist_ok=True)
    with bpy.context.temp_override(window=window):
        bpy.ops.screen.screenshot(filepath=os.path.join(OPTIONS.out, "window.png"))
    for name, area in (("shader-editor", editor), ("properties", props)):
        with bpy.context.temp_override(window=window, area=area, region=region(area, "WINDOW")):
            bpy.ops.screen.screenshot_area(filepath=os.path.join(OPTIONS.out, name + ".png"))
    print("panel_screenshots: drew %s" % sorted(DRAWN), flush=True)
    with bpy.context.temp_override(window=window):
        bpy.ops.wm.quit_blender()


def main():
    if "--enable-event-simulate" not in sys.argv:
        # Window.event_simulate needs it; it also makes Blender ignore the virtual
        # pointer, whose hover would make the screen operators' polls fail.
        raise RuntimeError("run Blender with --enable-event-simulate")
    guard = threading.Timer(TIMEOUT_S, lambda: (print("panel_screenshots: timeout"), os._exit(2)))
    guard.daemon = True  # a pending thread would keep Blender from quitting
    guard.start()
    view = bpy.context.preferences.view  # --factory-startup never saves preferences
    view.show_splash = False
    view.ui_scale = 1.25
    view.smooth_view = 0  # else view_all animates over several redraws
    window = bpy.context.window
    walk = steps(window)

    def tick():
        try:
            with bpy.context.temp_override(window=window):
                bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=1)
            next(walk)
        except StopIteration:
            return None
        except Exception:  # noqa: BLE001 -- any failure is the test's
            die()
        return 0.1

    bpy.app.timers.register(tick, first_interval=0.1)


try:
    main()
except Exception:  # noqa: BLE001
    die()
