# SPDX-License-Identifier: LGPL-2.1-or-later
# FemBspTet's App tests for FreeCAD's own test runner (registered in Init.py):
#     freecadcmd -t TestFemBspTetApp
# A quick check that the addon works inside FreeCAD's interpreter: the mesher object meshes a
# box with a hole, in SMESH's conventions, and every boundary node of every face is found by
# FemMesh.getNodesByFace. The full suite is tests/ (pytest, see README).
import unittest


class TestFemBspTetApp(unittest.TestCase):
    def setUp(self):
        import FreeCAD

        self.doc = FreeCAD.newDocument("TestFemBspTetApp")

    def tearDown(self):
        import FreeCAD

        FreeCAD.closeDocument(self.doc.Name)

    def test_mesher_object_meshes_and_constraints_find_the_nodes(self):
        import FreeCAD
        import Part

        import FemBspTet

        part = self.doc.addObject("Part::Feature", "Block")
        part.Shape = Part.makeBox(40, 20, 10).cut(
            Part.makeCylinder(5, 10, FreeCAD.Vector(20, 10, 0)))
        self.doc.recompute()
        obj = FemBspTet.make_mesher(self.doc, part, ElementOrder="1st", CompareWithPeers=False)
        self.assertEqual(obj.Proxy.Type, "Fem::FemMeshBspTet")
        result = FemBspTet.run_mesher(obj)
        fem = obj.FemMesh
        self.assertEqual(fem.NodeCount, len(result.mesh.points))
        self.assertGreater(fem.VolumeCount, 0)
        for k, face in enumerate(part.Shape.Faces):
            want = set((result.face_nodes(k) + 1).tolist())
            self.assertTrue(want and want <= set(fem.getNodesByFace(face)), "Face%d" % (k + 1))
        nodes = fem.Nodes
        n = fem.getElementNodes(fem.Volumes[0])
        a, b, c, d = (nodes[i] for i in n)
        self.assertLess((b - a).cross(c - a).dot(d - a), 0)  # SMESH orientation
