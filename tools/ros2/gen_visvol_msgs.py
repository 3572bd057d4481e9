#!/usr/bin/env python3
"""The ROS 2 message files of the visvol_msgs package, from the IDL.

  tools/ros2/gen_visvol_msgs.py IDL OUT_DIR

drivers/dds/idl/visvol_msgs.idl is the contract: every @final struct Name_
becomes OUT_DIR/Name.msg with the same fields in the same order (so a ROS 2
node's visvol_msgs/msg/Name is visvol_msgs::msg::dds_::Name_ on the wire), its
comments kept; each group of constants goes into the messages its heading
names ("// Objective (PathUpdate_.objective, Command_.objective)."). The
committed files under drivers/dds/ros2/visvol_msgs/msg are this script's
output; tests/drivers/dds/ros2_msgs_test.sh checks that they still are.
Exit status 0, 2 for an IDL it cannot read (naming the line).
"""
import os
import re
import sys

PRIMITIVES = {
    "boolean": "bool",
    "uint8": "uint8",
    "uint32": "uint32",
    "uint64": "uint64",
    "double": "float64",
    "string": "string",
    "std_msgs::msg::dds_::Header_": "std_msgs/Header",
    "geometry_msgs::msg::dds_::Point_": "geometry_msgs/Point",
}
HEADER = "# Generated from drivers/dds/idl/visvol_msgs.idl by tools/ros2/gen_visvol_msgs.py: do not edit.\n"


def fail(line_no, text):
    sys.stderr.write(f"gen_visvol_msgs: line {line_no}: {text}\n")
    sys.exit(2)


def ros_type(idl_type, line_no):
    m = re.fullmatch(r"sequence<\s*(.+?)\s*,\s*(\d+)\s*>", idl_type)
    if m:  # bounded
        return ros_type(m.group(1), line_no) + f"[<={m.group(2)}]"
    m = re.fullmatch(r"sequence<\s*(.+?)\s*>", idl_type)
    if m:
        return ros_type(m.group(1), line_no) + "[]"
    if idl_type in PRIMITIVES:
        return PRIMITIVES[idl_type]
    if re.fullmatch(r"[A-Z][A-Za-z0-9]*_", idl_type):
        return idl_type[:-1]  # a message of this package
    fail(line_no, f"no ROS 2 type for '{idl_type}'")


def comment_of(rest):
    rest = rest.strip()
    return rest[2:].strip() if rest.startswith("//") else ""


def parse(lines):
    """(constant groups [(targets, [(type, name, value, comment)])], structs {name: [entries]})"""
    groups, structs, order = [], {}, []
    inside = False
    current = None  # struct being read
    pending = []  # comment lines inside a struct, before the next field
    group = None
    for no, raw in enumerate(lines, 1):
        line = raw.strip()
        if "module visvol_msgs" in line:
            inside = True
            continue
        if not inside or not line:
            continue
        if current is not None:
            if line.startswith("};"):
                structs[current] = entries
                current = None
                continue
            if line.startswith("//"):
                indent = len(raw) - len(raw.lstrip())
                if entries and entries[-1][0] == "field" and entries[-1][3] and indent > field_indent + 8:
                    # a continuation of the field's own comment (indented to its column)
                    kind, t, n, c = entries[-1]
                    entries[-1] = (kind, t, n, c + " " + line[2:].strip())
                else:
                    pending.append(line[2:].strip())
                continue
            m = re.match(r"(sequence<[^>]+>|[A-Za-z_][A-Za-z0-9_:]*)\s+([a-z][a-z0-9_]*)\s*;(.*)$", line)
            if not m:
                fail(no, f"not a field: {line}")
            for c in pending:
                entries.append(("comment", c))
            pending = []
            field_indent = len(raw) - len(raw.lstrip())
            entries.append(("field", ros_type(m.group(1), no), m.group(2), comment_of(m.group(3))))
            continue
        if re.match(r"(@\w+\s+)*struct\b", line) and not line.startswith("@final"):
            fail(no, "a struct that is not @final (ROS 2's types are plain, final CDR)")
        m = re.match(r"@final\s+struct\s+([A-Z][A-Za-z0-9]*_)\s*\{", line)
        if m:
            current, entries, pending, field_indent = m.group(1)[:-1], [], [], 4
            order.append(current)
            group = None
            continue
        m = re.match(r"//.*\(([A-Z][A-Za-z0-9]*_\.[a-z_]+(?:\s*,\s*[A-Z][A-Za-z0-9]*_\.[a-z_]+)*)\)\.?\s*$", line)
        if m:
            targets = sorted({t.strip().split(".")[0][:-1] for t in m.group(1).split(",")})
            group = (targets, [])
            groups.append(group)
            continue
        m = re.match(r"const\s+(\w+)\s+([A-Z][A-Z0-9_]*)\s*=\s*(\d+)\s*;(.*)$", line)
        if m:
            if group is None:
                fail(no, f"constant {m.group(2)} under no heading that names its messages")
            group[1].append((ros_type(m.group(1), no), m.group(2), m.group(3), comment_of(m.group(4))))
            continue
    return groups, structs, order


def render(name, groups, entries):
    out = [HEADER]
    for targets, constants in groups:
        if name not in targets:
            continue
        for t, n, v, c in constants:
            out.append(f"{t} {n}={v}" + (f"  # {c}" if c else "") + "\n")
    if len(out) > 1:
        out.append("\n")
    for e in entries:
        if e[0] == "comment":
            out.append(f"# {e[1]}\n")
        else:
            _, t, n, c = e
            out.append(f"{t} {n}" + (f"  # {c}" if c else "") + "\n")
    return "".join(out)


def main(argv):
    if len(argv) != 3:
        sys.stderr.write("usage: gen_visvol_msgs.py IDL OUT_DIR\n")
        return 2
    with open(argv[1], encoding="utf-8") as f:
        lines = f.read().splitlines()
    groups, structs, order = parse(lines)
    for targets, _ in groups:
        for t in targets:
            if t not in structs:
                fail(0, f"constants name a message {t}_ that the IDL does not define")
    os.makedirs(argv[2], exist_ok=True)
    for name in order:
        with open(os.path.join(argv[2], name + ".msg"), "w", encoding="utf-8") as f:
            f.write(render(name, groups, structs[name]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
