# SPDX-License-Identifier: LGPL-2.1-or-later
"""Task panel of the BspTet mesher object: parameters, Apply/OK/Cancel, progress, Stop, the stats
and the TetGen comparison table.

* Apply writes the parameters to the object and meshes in a worker process
  (:class:`FemBspTet.freecad.mesh_worker.MeshJob`): the GUI thread only polls it from a QTimer, so
  FreeCAD never freezes, and a crash of the core cannot take FreeCAD down.
* Stop (or the dialog's Cancel) kills the worker at once; nothing of that run is kept.
* A failed run keeps the previous mesh and the document; the error goes to the report view and
  the panel's status line, and to ``obj.MeshStatus``.
* The mesh is set on the object on the GUI thread, in one undo transaction.
* OK writes the parameters and closes; it is refused while a run is going (Stop it first).
"""

import time

from ..compare.comparison import COLUMNS, OURS, Row, TETGEN_PY
from ..freecad.mesh_worker import MeshJob
from ..freecad.mesher_object import ROW_PROPERTIES
from ..freecad.mesher_tools import apply_result, parameters_from_object, record_failure, shape_of
from ..kernel.errors import BspTetError, InternalError, MeshingCancelled

#: Fields of the comparison rows the table shows (``compare.comparison.COLUMNS``; the values
#: come from the object's result properties, ``mesher_object.ROW_PROPERTIES``).
TABLE_FIELDS = ("nodes", "tets", "steiner_interior", "steiner_boundary", "min_dihedral_deg",
                "max_radius_edge_ratio", "seconds", "valid")
POLL_INTERVAL_MS = 100


class TaskPanelMeshBspTet:
    def __init__(self, obj):
        from PySide import QtCore

        self.obj = obj
        self.job = None
        self.last_result = None
        self.last_error = None
        self.form = self._build_form()
        self._timer = QtCore.QTimer()
        self._timer.setInterval(POLL_INTERVAL_MS)
        self._timer.timeout.connect(self._poll)
        self.load_parameters()
        self._show_object_results()

    # ---------------------------------------------------------------- form

    def _build_form(self):
        from PySide import QtGui

        form = QtGui.QWidget()
        form.setWindowTitle("BspTet mesh parameters")
        layout = QtGui.QVBoxLayout(form)

        params = QtGui.QGroupBox("Parameters")
        grid = QtGui.QFormLayout(params)
        self.sb_max = self._length_box(
            grid, "Max element size", "0 = automatic: the bounding-box diagonal / 20; curved "
            "faces and edges get smaller elements", "automatic")
        self.sb_min = self._length_box(grid, "Min element size",
                                       "0 = automatic: the max element size / 50", "automatic")
        self.cb_order = QtGui.QComboBox()
        self.cb_order.addItems(["1st", "2nd"])
        grid.addRow("Element order", self.cb_order)
        self.ck_groups = QtGui.QCheckBox("Face and node groups per CAD face")
        self.ck_tetgen = QtGui.QCheckBox("Compare with tetgen -pY")
        self.ck_tetgen.setToolTip("tetgen -pY on OpenCASCADE's display tessellation of the part "
                                  "(our mesh is made from the CAD faces themselves)")
        for ck in (self.ck_groups, self.ck_tetgen):
            grid.addRow(ck)
        layout.addWidget(params)

        run = QtGui.QGroupBox("Meshing")
        run_layout = QtGui.QVBoxLayout(run)
        self.progress = QtGui.QProgressBar()
        self.progress.setRange(0, 1000)
        self.progress.setValue(0)
        self.status = QtGui.QLabel("Apply meshes the part.")
        self.status.setWordWrap(True)
        self.bt_stop = QtGui.QPushButton("Stop meshing")
        self.bt_stop.setEnabled(False)
        self.bt_stop.clicked.connect(self.stop_meshing)
        run_layout.addWidget(self.progress)
        run_layout.addWidget(self.status)
        run_layout.addWidget(self.bt_stop)
        layout.addWidget(run)

        res = QtGui.QGroupBox("Result")
        res_layout = QtGui.QVBoxLayout(res)
        self.stats = QtGui.QLabel("")
        self.stats.setWordWrap(True)
        self.stats.setTextInteractionFlags(self.stats.textInteractionFlags() | 1)

        headers = dict((key, head) for key, head, _fmt in COLUMNS)
        self.table = QtGui.QTableWidget(len(TABLE_FIELDS), 2)
        self.table.setHorizontalHeaderLabels(["FemBspTet", "tetgen -pY"])
        self.table.setVerticalHeaderLabels([headers[k] for k in TABLE_FIELDS])
        self.table.setEditTriggers(QtGui.QAbstractItemView.NoEditTriggers)
        rows_height = sum(self.table.rowHeight(r) for r in range(len(TABLE_FIELDS)))
        self.table.setMinimumHeight(rows_height + self.table.horizontalHeader().height() + 4)
        res_layout.addWidget(self.stats)
        res_layout.addWidget(self.table)
        layout.addWidget(res)
        return form

    @staticmethod
    def _length_box(grid, label, tip, zero_text):
        from PySide import QtGui

        sb = QtGui.QDoubleSpinBox()
        sb.setSpecialValueText(zero_text)
        sb.setRange(0.0, 1e9)
        sb.setDecimals(4)
        sb.setSuffix(" mm")
        sb.setToolTip(tip)
        grid.addRow(label, sb)
        return sb

    # ---------------------------------------------------------------- parameters

    def load_parameters(self):
        o = self.obj
        self.sb_max.setValue(o.CharacteristicLengthMax.Value)
        self.sb_min.setValue(o.CharacteristicLengthMin.Value)
        self.cb_order.setCurrentIndex(0 if o.ElementOrder == "1st" else 1)
        self.ck_groups.setChecked(bool(o.FaceGroups))
        self.ck_tetgen.setChecked(bool(o.CompareWithTetGen))

    def store_parameters(self):
        o = self.obj
        o.CharacteristicLengthMax = self.sb_max.value()
        o.CharacteristicLengthMin = self.sb_min.value()
        o.ElementOrder = self.cb_order.currentText()
        o.FaceGroups = self.ck_groups.isChecked()
        o.CompareWithTetGen = self.ck_tetgen.isChecked()

    # ---------------------------------------------------------------- task dialog API

    def getStandardButtons(self):
        from PySide import QtGui

        b = QtGui.QDialogButtonBox
        return int(b.Ok) | int(b.Apply) | int(b.Cancel)

    def clicked(self, button):
        from PySide import QtGui

        if button == QtGui.QDialogButtonBox.Apply:
            self.start_meshing()

    def accept(self):
        import FreeCAD

        if self.running:
            self.status.setText("Meshing is still running: wait, or Stop it first.")
            FreeCAD.Console.PrintWarning("FemBspTet: meshing is still running; Stop it first\n")
            return False
        self.store_parameters()
        self._close()
        return True

    def reject(self):
        if self.running:
            self.stop_meshing()
        self._close()
        return True

    def _close(self):
        import FreeCADGui

        self._timer.stop()
        gui_doc = FreeCADGui.getDocument(self.obj.Document)
        if gui_doc is not None and gui_doc.getInEdit():
            gui_doc.resetEdit()

    # ---------------------------------------------------------------- meshing

    @property
    def running(self):
        return self.job is not None and self.job.running

    def start_meshing(self):
        """Write the parameters and start a worker. Returns False if it could not start."""
        import FreeCAD


        if self.running:
            self.status.setText("Meshing is already running.")
            return False
        self.store_parameters()
        self.last_result, self.last_error = None, None
        try:
            params = parameters_from_object(self.obj)
            self.job = MeshJob(shape_of(self.obj), params, source=self.obj.Label)
            self.job.start()
        except Exception as e:  # bad parameters, no shape, no worker interpreter, ...
            e = _as_bsptet_error(e)
            self.job = None
            self._failed(e)
            record_failure(self.obj, e)
            return False
        self.progress.setRange(0, 0)
        self.status.setText("Starting the meshing worker...")
        self.bt_stop.setEnabled(True)
        self._timer.start()
        FreeCAD.Console.PrintMessage("FemBspTet: meshing %s\n" % self.obj.Label)
        return True

    def stop_meshing(self):
        """Kill the running worker; the previous mesh stays."""
        import FreeCAD

        if self.job is None:
            return
        self._timer.stop()
        self.job.cancel()
        self.job = None
        self.bt_stop.setEnabled(False)
        self.progress.setRange(0, 1000)
        self.progress.setValue(0)
        self.last_error = MeshingCancelled("cancelled: no mesh was made")
        self.status.setText("Stopped. The previous mesh is kept.")
        FreeCAD.Console.PrintMessage("FemBspTet: meshing of %s stopped; previous mesh kept\n"
                                     % self.obj.Label)

    def _poll(self):
        if self.job is None:
            self._timer.stop()
            return
        for stage, fraction in self.job.poll():
            if fraction is None:
                self.progress.setRange(0, 0)
            else:
                self.progress.setRange(0, 1000)
                self.progress.setValue(int(round(1000 * min(max(fraction, 0.0), 1.0))))
            self.status.setText(stage)
        if self.job.running:
            return
        self._timer.stop()
        job, self.job = self.job, None
        self.bt_stop.setEnabled(False)
        self.progress.setRange(0, 1000)
        try:
            result = job.result()
        except Exception as e:  # the worker's error, or unreadable result files

            e = _as_bsptet_error(e)
            record_failure(self.obj, e)
            self.progress.setValue(0)
            self._failed(e)
            return
        self._apply(result)

    def wait(self, timeout=None):
        """Block until the running job ends, processing its events (scripts and tests)."""

        from PySide import QtGui

        start = time.monotonic()
        while self.job is not None:
            QtGui.QApplication.processEvents()
            self._poll()
            if timeout is not None and time.monotonic() - start > timeout:
                return False
            time.sleep(0.02)
        return True

    def _apply(self, result):
        import FreeCAD


        doc = self.obj.Document
        doc.openTransaction("Mesh with BspTet")
        try:
            apply_result(self.obj, result)
        except Exception as e:
            e = _as_bsptet_error(e)
            doc.abortTransaction()
            self._failed(e)
            return
        doc.commitTransaction()
        self.last_result = result
        self.progress.setValue(1000)
        self.status.setText(self.obj.MeshStatus)
        self._show_object_results()
        for note in result.notes:
            FreeCAD.Console.PrintWarning("FemBspTet: %s: %s\n" % (self.obj.Label, note))
        FreeCAD.Console.PrintMessage("FemBspTet: %s %s\n" % (self.obj.Label, self.obj.MeshStatus))

    def _failed(self, error):
        import FreeCAD

        self.last_error = error
        self.status.setText("Failed: %s\nThe previous mesh is kept." % error)
        FreeCAD.Console.PrintError("FemBspTet: meshing %s failed: %s\n" % (self.obj.Label, error))

    # ---------------------------------------------------------------- results

    def _show_object_results(self):
        """Stats and comparison table from the object's result properties."""
        from PySide import QtGui

        o = self.obj
        if not o.Nodes:
            self.stats.setText("Not meshed yet.")
        else:
            lines = ["%d nodes, %d tetrahedra (%s), %d Steiner points (%d on the surface)"
                     % (o.Nodes, o.Tetrahedra, o.ElementOrder, o.SteinerPoints,
                        o.BoundarySteinerPoints),
                     "dihedral angles from %.2f°, radius-edge ratio up to %.3g; %.2f s"
                     % (o.MinDihedralAngle, o.MaxRadiusEdgeRatio, o.MeshingTime)]
            lines += ["note: %s" % n for n in o.MeshNotes]
            self.stats.setText("\n".join(lines))
        ours, tetgen = object_rows(o)
        for row, field in enumerate(TABLE_FIELDS):
            for col, r in enumerate((ours, tetgen)):
                text = r.cell(field) if r is not None else "-"
                self.table.setItem(row, col, QtGui.QTableWidgetItem(text))
        if o.TetGenCommand:
            self.table.setToolTip(o.TetGenCommand)

    def comparison_table(self):
        """The table's cells as text rows (label, ours, TetGen): for tests and scripts."""
        rows = []
        for row in range(self.table.rowCount()):
            cells = [self.table.item(row, c) for c in (0, 1)]
            label = self.table.verticalHeaderItem(row).text()
            rows.append((label,) + tuple(c.text() if c is not None else "" for c in cells))
        return rows


def object_rows(obj):
    """``(ours, tetgen)``: comparison rows (``compare.comparison.Row``) rebuilt from the
    object's result properties, or None for a side without a mesh."""

    rows = []
    for mesher, present in ((OURS, obj.Nodes > 0), (TETGEN_PY, obj.TetGenTetrahedra > 0)):
        if not present:
            rows.append(None)
            continue
        props = ROW_PROPERTIES[mesher]
        values = {f: getattr(obj, p) for f, p in props.items() if f != "steiner_points"}
        values["steiner_interior"] = getattr(obj, props["steiner_points"]) - \
            values["steiner_boundary"]
        values.setdefault("valid", True)  # ours: checked exactly before it is returned
        values.setdefault("command", "fembsptet")
        rows.append(Row(mesher=mesher, **values))
    return tuple(rows)


def _as_bsptet_error(error):
    """``error`` itself if it is one of ours, else an InternalError that names it."""
    if isinstance(error, BspTetError):
        return error

    return InternalError("unexpected %s: %s" % (type(error).__name__, error))
