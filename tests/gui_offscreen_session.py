# SPDX-License-Identifier: LGPL-2.1-or-later
# Runs INSIDE FreeCAD's GUI (offscreen):
#     QT_QPA_PLATFORM=offscreen freecad gui_offscreen_session.py
# Driven by tests/test_gui_offscreen.py, which gives it a throw-away HOME with the checkout
# installed as a Mod (~/.local/share/FreeCAD/Mod/FemBspTet) and reads the facts it records
# (JSON, path in FEMBSPTET_GUI_OUT). It records what it sees and never decides pass/fail itself; every step is
# guarded so that one failure still reports the others. Ends with os._exit (FreeCAD's event loop
# would otherwise keep running).
import json
import os
import sys
import tempfile
import time
import traceback
import zipfile

facts = {"errors": []}
out_path = os.environ.get("FEMBSPTET_GUI_OUT",
                          os.path.join(tempfile.gettempdir(), "fembsptet_gui_out.json"))


def step(name):
    def wrap(fn):
        try:
            fn()
        except Exception:
            facts["errors"].append("%s: %s" % (name, traceback.format_exc()))
        return fn
    return wrap


try:
    import FreeCAD
    import FreeCADGui
    from PySide import QtCore, QtGui

    from FemBspTet.freecad.mesher_object import object_type, set_source, source_of

    facts["gui_up"] = bool(FreeCAD.GuiUp)

    @step("workbench and command")
    def _():
        facts["workbench_registered"] = "FemBspTetWorkbench" in FreeCADGui.listWorkbenches()
        facts["command_registered"] = "FEM_MeshBspTetFromShape" in FreeCADGui.listCommands()
        FreeCADGui.activateWorkbench("FemWorkbench")
        mw = FreeCADGui.getMainWindow()
        bars = {t.windowTitle(): [a.objectName() or a.text() for a in t.actions()]
                for t in mw.findChildren(QtGui.QToolBar)}
        facts["fem_toolbars"] = sorted(bars)
        facts["bsptet_toolbar_in_fem"] = bars.get("BspTet")
        facts["fem_toolbar_with_gmsh"] = next(
            (names for names in bars.values() if "FEM_MeshGmshFromShape" in names), None)
        facts["workbench_manipulators"] = hasattr(FreeCADGui, "addWorkbenchManipulator")
        from FemBspTet.gui import commands

        for _ in range(5):
            QtGui.QApplication.processEvents()
        menu = commands.fem_mesh_menu()
        facts["fem_mesh_menu_entries"] = ([a.objectName() for a in menu.actions()]
                                          if menu is not None else None)
        FreeCADGui.activateWorkbench("FemBspTetWorkbench")
        bars = {t.windowTitle(): [a.objectName() or a.text() for a in t.actions()]
                for t in mw.findChildren(QtGui.QToolBar) if t.isVisible()}
        facts["own_workbench_toolbar"] = bars.get("BspTet")
        FreeCADGui.activateWorkbench("FemWorkbench")

    import ObjectsFem
    import FemGui
    import Part

    doc = FreeCAD.newDocument("GuiTest")
    block = doc.addObject("Part::Feature", "Block")
    block.Shape = Part.makeBox(40, 20, 10).cut(
        Part.makeCylinder(5, 10, FreeCAD.Vector(20, 10, 0)))
    doc.recompute()
    analysis = ObjectsFem.makeAnalysis(doc, "Analysis")
    FemGui.setActiveAnalysis(analysis)
    state = {}

    @step("command creates the object")
    def _():
        FreeCADGui.Selection.clearSelection()
        FreeCADGui.Selection.addSelection(block)
        from FemBspTet.gui.commands import CommandMeshBspTetFromShape

        facts["command_active_with_selection"] = CommandMeshBspTetFromShape().IsActive()
        FreeCADGui.Selection.clearSelection()
        facts["command_active_without_selection"] = CommandMeshBspTetFromShape().IsActive()
        from FemBspTet.gui import commands

        for _ in range(3):
            QtGui.QApplication.processEvents()
        menu = commands.fem_mesh_menu()
        entry = [a for a in menu.actions() if a.objectName() == commands.COMMAND_NAME]
        menu.aboutToShow.emit()
        for _ in range(3):
            QtGui.QApplication.processEvents()
        facts["menu_entry_enabled_without_selection"] = entry[0].isEnabled() if entry else None
        facts["objects_before_command_without_selection"] = len(doc.Objects)
        FreeCADGui.runCommand(commands.COMMAND_NAME)  # does nothing, says so
        facts["objects_after_command_without_selection"] = len(doc.Objects)
        FreeCADGui.Selection.addSelection(block)
        FreeCADGui.runCommand("FEM_MeshBspTetFromShape")
        obj = doc.getObject("MeshBspTet")
        state["obj"] = obj
        facts["object_type"] = obj.TypeId
        facts["expected_object_type"] = object_type(doc)
        facts["proxy_type"] = obj.Proxy.Type
        facts["part_link"] = source_of(obj).Name
        facts["view_provider"] = type(obj.ViewObject.Proxy).__name__
        facts["in_analysis"] = obj in analysis.Group
        import __main__

        facts["created_through_doCommand"] = getattr(__main__, "_mesh", None) is obj
        facts["task_dialog_open_after_command"] = bool(FreeCADGui.Control.activeDialog())
        FreeCADGui.Control.closeDialog()
        FreeCADGui.ActiveDocument.resetEdit()

    @step("task panel meshes")
    def _():
        from FemBspTet.gui.task_panel import TaskPanelMeshBspTet

        obj = state["obj"]
        obj.ElementOrder = "1st"
        # a coarse mesh: FreeCAD 0.20.2's offscreen Coin3D crashes (SIGSEGV in
        # QuarterWidgetP::removeFromCacheContext) when a closed document's view held a mesh of
        # a few thousand tets (3,646 at the automatic size), in the save-and-reload step
        obj.CharacteristicLengthMax = 10
        FreeCADGui.ActiveDocument.setEdit(obj.Name)
        tp = obj.ViewObject.Proxy.task_panel
        facts["panel_is_ours"] = isinstance(tp, TaskPanelMeshBspTet)
        state["panel"] = tp
        t0 = time.monotonic()
        tp.bt_mesh.click()  # as a user does
        facts["apply_started"] = tp.job is not None
        facts["gui_responsive_while_meshing"] = tp.running  # start returned before the end
        facts["panel_finished"] = tp.wait(120)
        facts["panel_seconds"] = time.monotonic() - t0
        facts["panel_status"] = tp.status.text()
        facts["panel_stats"] = tp.stats.text()
        facts["panel_table"] = tp.comparison_table()
        facts["panel_progress"] = tp.progress.value()
        facts["panel_error"] = str(tp.last_error) if tp.last_error else None
        facts["nodes_after_mesh"] = obj.FemMesh.NodeCount
        facts["tets_after_mesh"] = obj.FemMesh.VolumeCount
        facts["result_nodes_property"] = obj.Nodes
        from FemBspTet.freecad.mesher_tools import comparison_rows

        facts["comparison_rows"] = [r.to_dict() for r in comparison_rows(obj)]
        facts["median_property"] = obj.MedianTetMinDihedralAngle
        facts["face_count_after_mesh"] = obj.FemMesh.FaceCount
        facts["group_count_after_mesh"] = obj.FemMesh.GroupCount
        facts["cad_faces"] = len(source_of(obj).Shape.Faces)
        # does the panel fit FreeCAD's combo view as it opens? (the task view is a scroll area)
        QtGui.QApplication.processEvents()
        mw = FreeCADGui.getMainWindow()
        areas = [a for a in mw.findChildren(QtGui.QScrollArea) if a.isAncestorOf(tp.form)]
        facts["panel_in_scroll_area"] = len(areas) == 1
        if areas:
            area = areas[0]
            view = area.viewport()
            facts["task_view_width"] = view.width()
            facts["panel_min_width"] = tp.form.minimumSizeHint().width()
            facts["panel_width"] = tp.form.width()
            facts["panel_parts_min_width"] = {
                w.title(): w.minimumSizeHint().width()
                for w in tp.form.findChildren(QtGui.QGroupBox)}
            facts["panel_table_min_width"] = tp.table.minimumSizeHint().width()
            facts["task_view_content_min_width"] = area.widget().minimumSizeHint().width()
            facts["task_view_parts_min_width"] = {
                w.metaObject().className().split("::")[-1]: w.minimumSizeHint().width()
                for w in area.widget().children() if isinstance(w, QtGui.QWidget)}
            facts["panel_wide_widgets"] = sorted(
                (max(w.minimumSizeHint().width(), w.minimumWidth()), w.metaObject().className(),
                 getattr(w, "text", lambda: "")() if hasattr(w, "text") else "")
                for w in tp.form.findChildren(QtGui.QWidget)
                if max(w.minimumSizeHint().width(), w.minimumWidth()) > 120)
            facts["panel_font"] = [tp.form.font().family(), tp.form.font().pointSizeF(),
                                   tp.form.fontMetrics().averageCharWidth()]
            facts["task_view_hscroll"] = area.horizontalScrollBar().maximum()
            docks = [d for d in mw.findChildren(QtGui.QDockWidget) if d.isAncestorOf(area)]
            top = docks[0] if docks else area
            buttons = [b for box in top.findChildren(QtGui.QDialogButtonBox)
                       for b in box.buttons() if b.isVisible()]
            facts["dialog_buttons"] = sorted(b.text().replace("&", "") for b in buttons)
            facts["panel_buttons"] = sorted(b.text() for b in tp.form.findChildren(
                QtGui.QPushButton) if b.isVisible())
            facts["dialog_buttons_inside"] = all(
                b.mapTo(top, QtCore.QPoint(b.width(), 0)).x() <= top.width() for b in buttons)
            table = tp.table
            facts["table_fits"] = table.mapTo(tp.form, QtCore.QPoint(table.width(), 0)).x() \
                <= view.width()
            facts["table_columns_fit"] = table.horizontalHeader().length() <= \
                table.viewport().width() and all(
                    table.columnWidth(c) >= max(table.sizeHintForColumn(c),
                                                table.horizontalHeader().sectionSizeHint(c))
                    for c in range(table.columnCount()))  # no text elided
        # the spin box keeps what it was given to the full precision
        obj.CharacteristicLengthMax = 10.123456789
        tp.load_parameters()
        tp.store_parameters()
        facts["size_after_store"] = obj.CharacteristicLengthMax.Value
        obj.CharacteristicLengthMax = 10
        tp.load_parameters()
        facts["mesh_status"] = obj.MeshStatus
        shot = os.environ.get("FEMBSPTET_GUI_SCREENSHOT")
        if shot:
            tp.form.resize(420, 900)
            tp.form.grab().save(shot)

    @step("stop keeps the previous mesh")
    def _():
        obj, tp = state["obj"], state["panel"]
        before = (obj.FemMesh.NodeCount, obj.FemMesh.VolumeCount, obj.MeshStatus)
        tp.sb_max.setValue(1.5)  # another mesh, were it kept
        facts["restart_started"] = tp.start_meshing()
        job = tp.job
        facts["running_before_stop"] = tp.running
        tp.stop_meshing()
        facts["worker_ended_after_stop"] = job._proc.poll() is not None
        facts["running_after_stop"] = tp.running
        QtGui.QApplication.processEvents()
        after = (obj.FemMesh.NodeCount, obj.FemMesh.VolumeCount, obj.MeshStatus)
        facts["mesh_kept_after_stop"] = before == after
        facts["status_after_stop"] = tp.status.text()

    @step("failure keeps the previous mesh")
    def _():
        obj, tp = state["obj"], state["panel"]
        shell = doc.addObject("Part::Feature", "OpenShell")
        shell.Shape = Part.Shell(Part.makeBox(5, 5, 5).Faces[:5])
        doc.recompute()
        before = (obj.FemMesh.NodeCount, obj.FemMesh.VolumeCount)
        set_source(obj, shell)
        obj.ElementDimension = "3D"  # an open shell has no volume to mesh
        tp.load_parameters()
        tp.sb_max.setValue(0.0)
        tp.start_meshing()
        tp.wait(120)
        facts["failure_error"] = str(tp.last_error)
        facts["failure_status_property"] = obj.MeshStatus
        facts["mesh_kept_after_failure"] = before == (obj.FemMesh.NodeCount,
                                                      obj.FemMesh.VolumeCount)
        set_source(obj, block)
        obj.ElementDimension = "From Shape"
        tp.load_parameters()
        doc.removeObject("OpenShell")

    @step("dialog buttons")
    def _():
        tp = state["panel"]
        facts["ok_closes"] = tp.accept()
        facts["dialog_open_after_ok"] = bool(FreeCADGui.Control.activeDialog())

    @step("double click opens the task panel")
    def _():
        obj = state["obj"]
        obj.ViewObject.Proxy.doubleClicked(obj.ViewObject)
        facts["dialog_open_after_double_click"] = bool(FreeCADGui.Control.activeDialog())
        tp = obj.ViewObject.Proxy.task_panel
        facts["reopened_progress"] = tp.progress.value()
        facts["reopened_status"] = tp.status.text()
        facts["mesh_status_at_reopen"] = obj.MeshStatus
        facts["reopened_progress_text_visible"] = tp.progress.isTextVisible()
        facts["reopened_table_rows"] = len([r for r in tp.comparison_table()[1:] if "-" not in r[1:]])
        FreeCADGui.Control.closeDialog()
        FreeCADGui.ActiveDocument.resetEdit()

    @step("save and reload")
    def _():
        obj = state["obj"]
        nodes = obj.FemMesh.NodeCount
        path = os.path.join(tempfile.mkdtemp(prefix="fembsptet_gui_"), "gui_test.FCStd")
        doc.saveAs(path)
        gui_xml = zipfile.ZipFile(path).read("GuiDocument.xml").decode()
        facts["gui_document_has_vp_module"] = "FemBspTet.gui.view_provider" in gui_xml
        FreeCAD.closeDocument(doc.Name)
        doc2 = FreeCAD.openDocument(path)
        o2 = doc2.getObject("MeshBspTet")
        facts["reloaded_nodes_equal"] = o2.FemMesh.NodeCount == nodes and nodes > 0
        facts["reloaded_proxy_type"] = getattr(o2.Proxy, "Type", None)
        facts["reloaded_view_provider"] = type(o2.ViewObject.Proxy).__name__
        facts["reloaded_part"] = source_of(o2).Name if source_of(o2) else None
        FreeCAD.closeDocument(doc2.Name)

    @step("preferences page")
    def _():
        import FemBspTet

        ui = os.path.join(os.path.dirname(os.path.dirname(FemBspTet.__file__)), "resources",
                          "ui", "PreferencesBspTet.ui")
        w = FreeCADGui.PySideUic.loadUi(ui)
        cb = w.findChild(QtGui.QComboBox, "cb_order")
        facts["prefs_combobox_class"] = cb.metaObject().className() if cb else None
        facts["prefs_checkboxes"] = sorted(c.objectName() for c in w.findChildren(QtGui.QCheckBox))
except Exception:
    facts["errors"].append("session: " + traceback.format_exc())
finally:
    with open(out_path, "w") as f:
        json.dump(facts, f, indent=1, default=str)
    sys.stdout.flush()
    os._exit(0)
