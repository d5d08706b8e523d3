# SPDX-License-Identifier: LGPL-2.1-or-later
# Runs INSIDE FreeCAD's GUI (scripts/freecad_screenshot.sh starts it under Xvfb): opens a CAD part,
# makes the BspTet mesher object through the FEM command, meshes it from the task panel, shows
# the mesh in the 3D view beside the panel and saves a picture of the main window.
# Environment: FEMBSPTET_SHOT_PART (CAD file), FEMBSPTET_SHOT_OUT (PNG), FEMBSPTET_SHOT_SIZE
# (window "WxH"). Ends with os._exit (FreeCAD's event loop would otherwise keep running).
import os
import sys
import time
import traceback

status = 1
try:
    import FreeCAD
    import FreeCADGui
    import FemGui
    import ObjectsFem
    import Part
    from PySide import QtGui

    part_path = os.environ["FEMBSPTET_SHOT_PART"]
    out = os.environ["FEMBSPTET_SHOT_OUT"]
    width, height = (int(v) for v in os.environ.get("FEMBSPTET_SHOT_SIZE", "1440x900").split("x"))

    def settle(seconds=0.5):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            QtGui.QApplication.processEvents()
            time.sleep(0.02)

    mw = FreeCADGui.getMainWindow()
    mw.showNormal()
    mw.resize(width, height)
    for dock in mw.findChildren(QtGui.QDockWidget):  # the panel gets the window's height
        if dock.objectName() in ("Python console", "Report view"):
            dock.hide()
    FreeCADGui.activateWorkbench("FemWorkbench")
    doc = FreeCAD.newDocument("Bracket")
    part = doc.addObject("Part::Feature", os.path.splitext(os.path.basename(part_path))[0])
    part.Shape = Part.read(part_path)
    doc.recompute()
    FemGui.setActiveAnalysis(ObjectsFem.makeAnalysis(doc, "Analysis"))
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(part)
    FreeCADGui.runCommand("FEM_MeshBspTetFromShape")  # makes the object, opens its panel
    mesher = doc.getObject("MeshBspTet")
    tp = mesher.ViewObject.Proxy.task_panel
    mesher.ElementOrder = "2nd"
    tp.load_parameters()
    if not tp.start_meshing() or not tp.wait(600) or tp.last_error is not None:
        raise RuntimeError("meshing failed: %s" % tp.last_error)
    part.ViewObject.Visibility = False
    mesher.ViewObject.Visibility = True
    view = FreeCADGui.ActiveDocument.ActiveView
    view.viewIsometric()
    view.fitAll()
    settle(1.5)
    # the screen's pixels, not the widget's: the 3D view is drawn by OpenGL
    shot = QtGui.QApplication.primaryScreen().grabWindow(mw.winId())
    if not shot.save(out):
        raise RuntimeError("could not write %s" % out)
    print("screenshot: %s (%d nodes, %d tets)" % (out, mesher.Nodes, mesher.Tetrahedra))
    status = 0
except Exception:
    traceback.print_exc()
finally:
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
