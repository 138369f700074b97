"""A .blend that Blender opens with an error report and loads all the same, as real files
do: its one sequencer strip sits on channel 200, above the 128 channels every Blender
reads, so opening it reports "1 sequence strips were not read because they were in a
channel larger than 128" (bpy raises that as a RuntimeError) and loads everything else.
Blender will not put a strip there itself, so the saved file is patched: the strip's
`machine` field, found through the file's own DNA. Beside it, a rough single-scatter GGX
material to audit and fix.

    blender -b --factory-startup --python unreadable_strip.py -- OUT.blend
"""
import struct
import sys

import bpy

CHANNEL = 200


def build(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    material = bpy.data.materials.new("rough-ggx")
    material.use_nodes = True
    material.use_fake_user = True
    glossy = material.node_tree.nodes.new("ShaderNodeBsdfGlossy")
    glossy.distribution = "GGX"
    glossy.inputs["Roughness"].default_value = 1.0
    material.node_tree.links.new(glossy.outputs[0],
                                 material.node_tree.nodes["Material Output"].inputs[0])
    scene = bpy.context.scene
    editor = scene.sequence_editor_create()
    strips = editor.strips if hasattr(editor, "strips") else editor.sequences
    strips.new_effect(name="unreadable", type="COLOR", channel=1, frame_start=1, frame_end=10)
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=False)


def blocks(data):
    """(code, data offset, length, SDNA index, count) of every block of a file with the
    12-byte header that 3.x writes."""
    assert data[:7] == b"BLENDER" and data[7:8] in b"-_", data[:12]
    pointer = 8 if data[7:8] == b"-" else 4
    order = "<" if data[8:9] == b"v" else ">"
    head = order + ("iQii" if pointer == 8 else "iIii")
    offset, found = 12, []
    while offset < len(data):
        code = bytes(data[offset:offset + 4])
        length, _old, sdna, count = struct.unpack_from(head, data, offset + 4)
        start = offset + 4 + struct.calcsize(head)
        found.append((code, start, length, sdna, count))
        if code == b"ENDB":
            break
        offset = start + length
    return order, pointer, found


def structs(data, order, dna):
    """[(type name, [(type name, field name, type length)])] of the DNA1 block."""
    position = dna + 4  # "SDNA"

    def section(tag):
        nonlocal position
        position = (position + 3) & ~3
        assert data[position:position + 4] == tag, tag
        position += 4

    def names():
        nonlocal position
        (count,) = struct.unpack_from(order + "i", data, position)
        position += 4
        out = []
        for _ in range(count):
            end = data.index(b"\0", position)
            out.append(data[position:end].decode())
            position = end + 1
        return out

    section(b"NAME")
    fields = names()
    section(b"TYPE")
    types = names()
    section(b"TLEN")
    lengths = struct.unpack_from(order + "%dh" % len(types), data, position)
    position += 2 * len(types)
    section(b"STRC")
    (count,) = struct.unpack_from(order + "i", data, position)
    position += 4
    out = []
    for _ in range(count):
        kind, n = struct.unpack_from(order + "hh", data, position)
        position += 4
        members = []
        for _ in range(n):
            t, f = struct.unpack_from(order + "hh", data, position)
            position += 4
            members.append((types[t], fields[f], lengths[t]))
        out.append((types[kind], members))
    return out


def field_offset(members, wanted, pointer):
    offset = 0
    for _type, name, length in members:
        count = 1
        for part in name.split("[")[1:]:
            count *= int(part.split("]")[0])
        size = pointer if "*" in name else length
        if name.split("[")[0] == wanted:
            return offset
        offset += size * count
    raise KeyError(wanted)


def move_strips(path, channel):
    data = bytearray(open(path, "rb").read())
    order, pointer, found = blocks(data)
    dna = next(start for code, start, *_ in found if code == b"DNA1")
    kinds = structs(data, order, dna)
    # 3.x and 4.x call a strip Sequence (and its data Strip); 5.0 renamed it Strip.
    names = [name for name, _ in kinds]
    index = names.index("Sequence" if "Sequence" in names else "Strip")
    machine = field_offset(kinds[index][1], "machine", pointer)
    moved = 0
    for code, start, length, sdna, count in found:
        if code == b"DATA" and sdna == index:
            for i in range(count):
                struct.pack_into(order + "i", data, start + i * (length // count) + machine,
                                 channel)
                moved += 1
    assert moved == 1, moved
    with open(path, "wb") as out:
        out.write(data)


if __name__ == "__main__":
    out = sys.argv[-1]
    build(out)
    move_strips(out, CHANNEL)
