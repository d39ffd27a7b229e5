"""A URDF read back from its file, and its forward kinematics vectorised over waypoints.

Reading the file rather than the Python description checks the file itself: the true robot and
every baseline here use the URDF exactly as a user's software would.

URDF semantics (wiki.ros.org/urdf/XML/joint): a joint's frame is its parent link's frame moved
by `<origin xyz rpy>`; the child link's frame is the joint frame moved by the joint's motion —
a rotation by q about `<axis>` (revolute) or a translation q·axis (prismatic); `<mimic>` makes
q = multiplier·q_source + offset. `<inertial><origin>` is the centre of mass in the link frame.

The forward map takes the true robot's perturbations as hooks, so the nominal and the true
robot share one implementation of the URDF's conventions:
* `joint_delta` — added to a joint's value (compliance, backlash),
* `origin_scale` — a factor on a joint's origin xyz (thermal expansion of its parent link),
* `motion_scale` — a factor on a prismatic joint's travel (the column's screw expanding),
* `origin_offset` — added to a joint's origin xyz (the prism's true offset),
* `link_premultiply` — a transform in the root frame applied to a link's frame and so to
  everything outboard of it (the column top's deflection).
"""

import xml.etree.ElementTree as ET

import numpy as np

from rotations import axis_angle_matrices, rpy_matrix


def _floats(text, default):
    return np.array([float(x) for x in text.split()]) if text is not None else np.array(default, dtype=float)


class Urdf:
    def __init__(self, path):
        root = ET.parse(path).getroot()
        self.links = {}
        for link in root.findall("link"):
            inertial = link.find("inertial")
            mass, com = 0.0, np.zeros(3)
            if inertial is not None:
                mass = float(inertial.find("mass").get("value"))
                o = inertial.find("origin")
                com = _floats(o.get("xyz") if o is not None else None, [0, 0, 0])
            self.links[link.get("name")] = {"mass": mass, "com": com}
        self.joints = {}
        for j in root.findall("joint"):
            o = j.find("origin")
            axis = j.find("axis")
            mimic = j.find("mimic")
            limit = j.find("limit")
            self.joints[j.get("name")] = {
                "type": j.get("type"), "parent": j.find("parent").get("link"), "child": j.find("child").get("link"),
                "xyz": _floats(o.get("xyz") if o is not None else None, [0, 0, 0]),
                "rpy": _floats(o.get("rpy") if o is not None else None, [0, 0, 0]),
                "axis": _floats(axis.get("xyz") if axis is not None else None, [1, 0, 0]),
                "mimic": None if mimic is None else {"joint": mimic.get("joint"), "multiplier": float(mimic.get("multiplier", 1.0)),
                                                     "offset": float(mimic.get("offset", 0.0))},
                "limit": None if limit is None else (float(limit.get("lower", 0)), float(limit.get("upper", 0))),
            }
        self.child_joints = {}
        for name, j in self.joints.items():
            self.child_joints.setdefault(j["parent"], []).append(name)
        children = {j["child"] for j in self.joints.values()}
        roots = [l for l in self.links if l not in children]
        assert len(roots) == 1, f"a URDF tree has one root link, found {roots}"
        self.root = roots[0]
        self.order = self._topological_joints()

    def _topological_joints(self):
        order, stack = [], [self.root]
        while stack:
            link = stack.pop()
            for jn in self.child_joints.get(link, []):
                order.append(jn)
                stack.append(self.joints[jn]["child"])
        return order

    def movable_joints(self):
        return [n for n in self.order if self.joints[n]["type"] in ("revolute", "prismatic", "continuous")]

    def independent_joints(self):
        return [n for n in self.movable_joints() if self.joints[n]["mimic"] is None]

    def full_joint_values(self, q):
        """{independent joint: (N,)} → {every movable joint: (N,)}, mimics resolved."""
        full = dict(q)
        for n in self.movable_joints():
            m = self.joints[n]["mimic"]
            if m is not None:
                full[n] = m["multiplier"] * np.asarray(full[m["joint"]]) + m["offset"]
        return full

    def subtree_links(self, joint):
        """The links outboard of a joint (its child and everything below it)."""
        out, stack = [], [self.joints[joint]["child"]]
        while stack:
            link = stack.pop()
            out.append(link)
            stack += [self.joints[jn]["child"] for jn in self.child_joints.get(link, [])]
        return out

    def forward(self, q, joint_delta=None, origin_scale=None, motion_scale=None, origin_offset=None, link_premultiply=None):
        """Frames in the root link's frame: ({link: (N,4,4)}, {joint: (N,4,4) joint frame before its motion}).

        q: {movable joint: (N,)} (mimics included: `full_joint_values`)."""
        joint_delta, origin_scale = joint_delta or {}, origin_scale or {}
        motion_scale, origin_offset, link_premultiply = motion_scale or {}, origin_offset or {}, link_premultiply or {}
        n = len(next(iter(q.values())))
        frames = {self.root: np.repeat(np.eye(4)[None], n, axis=0)}
        joint_frames = {}
        for jn in self.order:
            j = self.joints[jn]
            xyz = j["xyz"] + np.asarray(origin_offset.get(jn, 0.0))
            scale = np.asarray(origin_scale.get(jn, 1.0), dtype=float)
            xyz = xyz[None, :] * np.broadcast_to(scale, (n,))[:, None]
            origin = np.repeat(np.eye(4)[None], n, axis=0)
            origin[:, :3, :3] = rpy_matrix(j["rpy"])
            origin[:, :3, 3] = xyz
            jf = frames[j["parent"]] @ origin
            joint_frames[jn] = jf
            motion = np.repeat(np.eye(4)[None], n, axis=0)
            if j["type"] in ("revolute", "continuous"):
                angle = np.asarray(q[jn], dtype=float) + np.asarray(joint_delta.get(jn, 0.0))
                motion[:, :3, :3] = axis_angle_matrices(j["axis"] / np.linalg.norm(j["axis"]), angle)
            elif j["type"] == "prismatic":
                d = (np.asarray(q[jn], dtype=float) + np.asarray(joint_delta.get(jn, 0.0))) * np.asarray(motion_scale.get(jn, 1.0))
                motion[:, :3, 3] = np.outer(d, j["axis"] / np.linalg.norm(j["axis"]))
            child = jf @ motion
            if j["child"] in link_premultiply:
                child = link_premultiply[j["child"]] @ child
            frames[j["child"]] = child
        return frames, joint_frames

    def centres_of_mass(self, frames, links):
        """{link: (N,3)} centres of mass in the root frame."""
        return {l: np.einsum("nij,j->ni", frames[l][:, :3, :3], self.links[l]["com"]) + frames[l][:, :3, 3] for l in links}

    def joint_axis_in_root(self, joint_frames, joint):
        a = self.joints[joint]["axis"] / np.linalg.norm(self.joints[joint]["axis"])
        return np.einsum("nij,j->ni", joint_frames[joint][:, :3, :3], a)
