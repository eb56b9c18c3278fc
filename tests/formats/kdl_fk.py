#!/usr/bin/python3
"""Forward kinematics of a URDF chain by an independent reader: the XML read with Python's
ElementTree (not urdfdom), the chain built and solved by Orocos KDL (Debian's python3-pykdl).

usage: kdl_fk.py URDF BASE_LINK TIP_LINK JOINTS_CSV

JOINTS_CSV: one row per joint vector, the chain's movable joints' values in radians, in chain
order from BASE_LINK to TIP_LINK. Prints one row per input row: the pose of TIP_LINK in
BASE_LINK's frame, x y z (meters) and the rotation matrix row by row (9 numbers), %.17g.
Exit 1 with a message on stderr for a chain it cannot build.
"""
import math
import sys
import xml.etree.ElementTree as ET

import PyKDL as kdl


def numbers(text, count, default):
    if text is None:
        return default
    values = [float(v) for v in text.split()]
    if len(values) != count:
        raise ValueError(f"expected {count} numbers, got '{text}'")
    return values


def origin_frame(joint):
    origin = joint.find("origin")
    xyz = numbers(origin.get("xyz") if origin is not None else None, 3, [0.0, 0.0, 0.0])
    rpy = numbers(origin.get("rpy") if origin is not None else None, 3, [0.0, 0.0, 0.0])
    # URDF's rpy is fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll), KDL's RPY.
    return kdl.Frame(kdl.Rotation.RPY(*rpy), kdl.Vector(*xyz))


def chain_joints(root, base, tip):
    by_child = {j.find("child").get("link"): j for j in root.findall("joint")}
    joints = []
    link = tip
    while link != base:
        if link not in by_child:
            raise ValueError(f"link '{base}' is not above link '{tip}'")
        joint = by_child[link]
        joints.append(joint)
        link = joint.find("parent").get("link")
    return list(reversed(joints))


def build_chain(path, base, tip):
    root = ET.parse(path).getroot()
    chain = kdl.Chain()
    movable = 0
    for joint in chain_joints(root, base, tip):
        kind = joint.get("type")
        # The joint's origin as a fixed segment, then the rotation about its axis.
        chain.addSegment(kdl.Segment(joint.get("name") + "_origin", kdl.Joint(kdl.Joint.Fixed),
                                     origin_frame(joint)))
        if kind == "fixed":
            continue
        if kind not in ("revolute", "continuous"):
            raise ValueError(f"joint '{joint.get('name')}' is {kind}")
        axis_element = joint.find("axis")
        axis = numbers(axis_element.get("xyz") if axis_element is not None else None, 3,
                       [1.0, 0.0, 0.0])
        norm = math.sqrt(sum(a * a for a in axis))
        axis = kdl.Vector(*(a / norm for a in axis))
        chain.addSegment(kdl.Segment(joint.get("name"),
                                     kdl.Joint(joint.get("name"), kdl.Vector(0, 0, 0), axis,
                                               kdl.Joint.RotAxis),
                                     kdl.Frame.Identity()))
        movable += 1
    return chain, movable


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    path, base, tip, joints_csv = sys.argv[1:]
    try:
        chain, movable = build_chain(path, base, tip)
    except (ValueError, ET.ParseError) as e:
        print(f"kdl_fk.py: {path}: {e}", file=sys.stderr)
        sys.exit(1)
    solver = kdl.ChainFkSolverPos_recursive(chain)
    out = []
    with open(joints_csv) as f:
        for line_number, line in enumerate(f, 1):
            values = [float(v) for v in line.strip().split(",")]
            if len(values) != movable:
                print(f"kdl_fk.py: {joints_csv}:{line_number}: {len(values)} values for "
                      f"{movable} joints", file=sys.stderr)
                sys.exit(1)
            q = kdl.JntArray(movable)
            for i, v in enumerate(values):
                q[i] = v
            frame = kdl.Frame()
            if solver.JntToCart(q, frame) < 0:
                print(f"kdl_fk.py: KDL could not solve row {line_number}", file=sys.stderr)
                sys.exit(1)
            row = [frame.p[i] for i in range(3)] + [frame.M[r, c] for r in range(3)
                                                     for c in range(3)]
            out.append(" ".join("%.17g" % v for v in row))
    print("\n".join(out))


if __name__ == "__main__":
    main()
