"""Geometry shared by several stages (placeholder on branch redesign-c2: the geometry
package and this file belong to redesign-c1; keep theirs on merge and add
``from ._mesh import Mesh``)."""
