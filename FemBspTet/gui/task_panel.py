# SPDX-License-Identifier: LGPL-2.1-or-later
"""Task panel of the BspTet mesher object: parameters, Mesh and Stop, progress, OK/Cancel, the
stats and the comparison at the same size (our mesh, TetGen's, Gmsh's and Netgen's: a column each).

* Mesh writes the parameters to the object and meshes in a worker process
  (:class:`FemBspTet.freecad.mesh_worker.MeshJob`): the GUI thread only polls it from a QTimer, so
  FreeCAD never freezes, and a crash of the core cannot take FreeCAD down.
* Stop (or the dialog's Cancel) kills the worker at once; nothing of that run is kept.
* A failed run keeps the previous mesh and the document; the error goes to the report view and
  the panel's status line, and to ``obj.MeshStatus``.
* The mesh is set on the object on the GUI thread, in one undo transaction.
* OK writes the parameters and closes; it is refused while a run is going (Stop it first).
* The panel fits FreeCAD's default combo view width (short labels, wrapping texts, one short
  column per mesher); the lengths are FreeCAD quantities in the user's units.
"""

import time

from ..compare.at_size import OURS, PEERS
from ..freecad.mesh_worker import MeshJob
from ..freecad.mesher_object import DIMENSIONS
from ..freecad.mesher_tools import (apply_result, comparison_rows, parameters_from_object,
                                    record_failure, shape_of)
from ..kernel.errors import BspTetError, InternalError, MeshingCancelled

def compact_count(n):
    """A count in at most five characters: 9094, 14.1k, 1.23M."""
    n = int(n)
    if n < 10000:
        return str(n)
    if n < 999500:
        return "%.3gk" % (n / 1e3)
    return "%.3gM" % (n / 1e6)


#: Rows of the comparison table: (header, tooltip, cell text of a SizeRow).
TABLE_ROWS = (
    ("nodes", "Nodes (mid-nodes included)", lambda r: compact_count(r.nodes)),
    ("tets", "Tetrahedra", lambda r: compact_count(r.tets)),
    ("min°", "Smallest dihedral angle (degrees)", lambda r: "%.1f" % r.min_dihedral_deg),
    ("med°", "Median over the tetrahedra of each one's smallest dihedral angle (degrees)",
     lambda r: "%.1f" % r.median_tet_min_dihedral_deg),
    ("s", "Seconds", lambda r: "%.2f" % r.seconds if r.seconds < 10 else
     "%.1f" % r.seconds if r.seconds < 100 else "%d" % r.seconds),
)
#: Columns of the comparison table: (header, mesher of the comparison rows).
TABLE_MESHERS = (("ours", OURS),) + tuple((peer, peer) for peer in PEERS)
POLL_INTERVAL_MS = 100
#: The comparison table's font size at most (points): small enough for its four columns to fit
#: FreeCAD's default combo view at a 12-point panel font.
TABLE_POINT_SIZE = 7.8
#: Contents margins of the panel's group boxes (left, top, right, bottom), in pixels.
MARGINS = (4, 6, 4, 4)


class LengthField:
    """A length in FreeCAD's units (``Gui::InputField``, as FEM's Gmsh panel), holding the exact
    value it was given until the user edits it: an unedited field never rounds the property to
    the digits it shows. ``value()`` / ``setValue()`` in mm."""

    def __init__(self, tip):
        import FreeCADGui
        from PySide import QtCore

        self.widget = FreeCADGui.UiLoader().createWidget("Gui::InputField")
        self.widget.setProperty("unit", "mm")
        self.widget.setProperty("minimum", 0.0)
        self.widget.setToolTip(tip)
        self.widget.setMinimumWidth(80)  # the field's own hint is wider than the combo view needs
        self._value = 0.0
        QtCore.QObject.connect(self.widget, QtCore.SIGNAL("valueChanged(Base::Quantity)"),
                               self._edited)

    def _edited(self, quantity):
        self._value = float(quantity.Value)

    def value(self):
        return self._value

    def setValue(self, mm):
        import FreeCAD

        self._value = float(mm)
        self.widget.blockSignals(True)
        try:
            self.widget.setText(FreeCAD.Units.Quantity(self._value, FreeCAD.Units.Length)
                                .UserString)
        finally:
            self.widget.blockSignals(False)


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
        """Narrow enough for FreeCAD's default combo view: short labels, texts that wrap, the
        comparison as one short column per mesher."""
        from PySide import QtCore, QtGui

        form = QtGui.QWidget()
        form.setWindowTitle("BspTet mesh")
        layout = QtGui.QVBoxLayout(form)
        layout.setContentsMargins(0, 0, 0, 0)  # the task box has its own

        params = QtGui.QGroupBox("Parameters")
        grid = QtGui.QFormLayout(params)
        grid.setContentsMargins(*MARGINS)
        grid.setRowWrapPolicy(QtGui.QFormLayout.WrapLongRows)
        self.sb_max = LengthField("Largest element size; 0 = automatic: the bounding-box "
                                  "diagonal / 20. Curved faces and edges get smaller elements")
        self.sb_min = LengthField("Smallest element size; 0 = automatic: the max size / 50")
        grid.addRow("Max size:", self.sb_max.widget)
        grid.addRow("Min size:", self.sb_min.widget)
        self.cb_dimension = QtGui.QComboBox()
        self.cb_dimension.addItems(list(DIMENSIONS))
        self.cb_dimension.setToolTip("3D: tetrahedra of the solids; 2D: triangles of the faces "
                                     "(shells, plates); From Shape: 3D with a solid, else 2D")
        grid.addRow("Dimension:", self.cb_dimension)
        self.cb_order = QtGui.QComboBox()
        self.cb_order.addItems(["1st", "2nd"])
        grid.addRow("Order:", self.cb_order)
        self.ck_groups = QtGui.QCheckBox("Face groups")
        self.ck_groups.setToolTip("The boundary triangles as FemMesh faces (tria6 for 2nd "
                                  "order), a face group and a node group per CAD face")
        self.ck_compare = QtGui.QCheckBox("Compare with peers")
        self.ck_compare.setToolTip("Also mesh the part at the same size with TetGen (tetgen -pq "
                                   "with the matching volume bound, on this mesh's surface), "
                                   "Gmsh and Netgen (on the CAD part, where installed)")
        for ck in (self.ck_groups, self.ck_compare):
            grid.addRow(ck)
        layout.addWidget(params)

        run = QtGui.QGroupBox("Meshing")
        run_layout = QtGui.QGridLayout(run)
        run_layout.setContentsMargins(*MARGINS)
        self.progress = QtGui.QProgressBar()
        self.progress.setRange(0, 1000)
        self.progress.setValue(0)
        self.progress.setTextVisible(False)  # a percentage only while a run goes on
        self.bt_stop = QtGui.QPushButton("Stop")
        self.bt_stop.setToolTip("Stop meshing; the previous mesh is kept")
        self.bt_stop.setEnabled(False)
        self.bt_stop.clicked.connect(self.stop_meshing)
        self.bt_mesh = QtGui.QPushButton("Mesh")
        self.bt_mesh.setToolTip("Write the parameters and mesh the part (in the background)")
        self.bt_mesh.clicked.connect(lambda: self.start_meshing())
        self.status = QtGui.QLabel("Mesh meshes the part.")
        self.status.setWordWrap(True)
        run_layout.addWidget(self.bt_mesh, 0, 0)
        run_layout.addWidget(self.bt_stop, 0, 1)
        run_layout.addWidget(self.progress, 1, 0, 1, 2)
        run_layout.addWidget(self.status, 2, 0, 1, 2)
        layout.addWidget(run)

        res = QtGui.QGroupBox("Result")
        res.setFlat(True)  # no frame: the table has its own
        res_layout = QtGui.QVBoxLayout(res)
        res_layout.setContentsMargins(0, MARGINS[1], 0, 0)  # the table's own frame is enough
        self.stats = QtGui.QLabel("")
        self.stats.setWordWrap(True)
        self.stats.setTextInteractionFlags(self.stats.textInteractionFlags() | 1)
        self.table = QtGui.QTableWidget(len(TABLE_ROWS), len(TABLE_MESHERS))
        self.table.setHorizontalHeaderLabels([head for head, _mesher in TABLE_MESHERS])
        for row, (head, tip, _cell) in enumerate(TABLE_ROWS):
            item = QtGui.QTableWidgetItem(head)
            item.setToolTip(tip)
            self.table.setVerticalHeaderItem(row, item)
        self.table.setEditTriggers(QtGui.QAbstractItemView.NoEditTriggers)
        self.table.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)
        self.table.setVerticalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)
        self.table.verticalHeader().setDefaultSectionSize(
            self.table.fontMetrics().height() + 6)
        self.table.horizontalHeader().setMinimumSectionSize(8)
        small = self.table.font()
        small.setPointSizeF(min(small.pointSizeF(), TABLE_POINT_SIZE))
        for part in (self.table, self.table.horizontalHeader(), self.table.verticalHeader()):
            part.setFont(small)
        res_layout.addWidget(self.stats)
        res_layout.addWidget(self.table)
        layout.addWidget(res)
        layout.addStretch(1)
        return form

    def _fit_table(self):
        """Each column as wide as its widest text (Qt's own measure, cell margins included),
        the table as large as its cells: all of it visible without scrolling."""
        t = self.table
        t.resizeColumnsToContents()
        t.verticalHeader().setFixedWidth(t.verticalHeader().sizeHint().width())
        frame = 2 * t.frameWidth()
        t.setFixedHeight(t.horizontalHeader().height() + frame + sum(
            t.rowHeight(r) for r in range(t.rowCount())))
        t.setFixedWidth(t.verticalHeader().width() + frame + sum(
            t.columnWidth(c) for c in range(t.columnCount())))

    # ---------------------------------------------------------------- parameters

    def load_parameters(self):
        o = self.obj
        self.sb_max.setValue(o.CharacteristicLengthMax.Value)
        self.sb_min.setValue(o.CharacteristicLengthMin.Value)
        self.cb_dimension.setCurrentIndex(DIMENSIONS.index(o.ElementDimension))
        self.cb_order.setCurrentIndex(0 if o.ElementOrder == "1st" else 1)
        self.ck_groups.setChecked(bool(o.FaceGroups))
        self.ck_compare.setChecked(bool(o.CompareWithPeers))

    def store_parameters(self):
        o = self.obj
        for prop, field in (("CharacteristicLengthMax", self.sb_max),
                            ("CharacteristicLengthMin", self.sb_min)):
            if getattr(o, prop).Value != field.value():
                setattr(o, prop, field.value())
        o.ElementDimension = self.cb_dimension.currentText()
        o.ElementOrder = self.cb_order.currentText()
        o.FaceGroups = self.ck_groups.isChecked()
        o.CompareWithPeers = self.ck_compare.isChecked()

    # ---------------------------------------------------------------- task dialog API

    def getStandardButtons(self):
        from PySide import QtGui

        # No Apply: the panel's own Mesh button does it, and OK, Cancel and Apply side by side
        # are wider than FreeCAD's default combo view.
        b = QtGui.QDialogButtonBox
        return int(b.Ok) | int(b.Cancel)

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
        self.progress.setTextVisible(True)
        self.status.setText("Starting the meshing worker...")
        self._show_running(True)
        self._timer.start()
        FreeCAD.Console.PrintMessage("FemBspTet: meshing %s\n" % self.obj.Label)
        return True

    def _show_running(self, running):
        self.bt_stop.setEnabled(running)
        self.bt_mesh.setEnabled(not running)

    def stop_meshing(self):
        """Kill the running worker; the previous mesh stays."""
        import FreeCAD

        if self.job is None:
            return
        self._timer.stop()
        self.job.cancel()
        self.job = None
        self._show_running(False)
        self.progress.setRange(0, 1000)
        self.progress.setValue(0)
        self.progress.setTextVisible(False)
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
        self._show_running(False)
        self.progress.setRange(0, 1000)
        self.progress.setTextVisible(False)
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
        """Stats, status, progress and the comparison table from the object's result
        properties (also when the panel is reopened on an old mesh)."""
        from PySide import QtCore, QtGui

        o = self.obj
        if not o.Nodes:
            self.stats.setText("Not meshed yet.")
        else:
            if o.Triangles:  # 2D
                lines = ["%d nodes, %d triangles (%s order); %.1f s"
                         % (o.Nodes, o.Triangles, o.ElementOrder, o.MeshingTime)]
            else:
                lines = ["%d nodes, %d tetrahedra (%s order)" % (o.Nodes, o.Tetrahedra,
                                                                  o.ElementOrder),
                         "smallest dihedral angle %.1f°, median per-tet smallest %.1f°"
                         % (o.MinDihedralAngle, o.MedianTetMinDihedralAngle),
                         "%d points added to the surface mesh (%d on the CAD faces); %.1f s"
                         % (o.SteinerPoints, o.BoundarySteinerPoints, o.MeshingTime)]
            lines += ["note: %s" % n for n in o.MeshNotes]
            self.stats.setText("\n".join(lines))
            if not self.running:
                self.progress.setValue(1000 if o.MeshStatus.startswith("meshed") else 0)
                self.status.setText(o.MeshStatus if o.MeshStatus.startswith("meshed") else
                                    "%s\nThe mesh shown is the one before." % o.MeshStatus)
        rows = {r.mesher: r for r in comparison_rows(o)}
        tips = []
        for col, (head, mesher) in enumerate(TABLE_MESHERS):
            r = rows.get(mesher)
            about = "" if r is None else r.command if r.status == "ok" else \
                "%s (%s)" % (r.status, r.message)
            for row, (_head, _tip, cell) in enumerate(TABLE_ROWS):
                item = QtGui.QTableWidgetItem(cell(r) if r is not None and r.status == "ok"
                                              else "-")
                item.setTextAlignment(int(QtCore.Qt.AlignRight | QtCore.Qt.AlignVCenter))
                item.setToolTip("%s: %s" % (mesher, about) if about else mesher)
                self.table.setItem(row, col, item)
            if about:
                tips.append("%s: %s" % (head, about))
        self.table.setToolTip("\n".join(tips))
        self._fit_table()

    def comparison_table(self):
        """The table's cells as text rows (header, then one cell per mesher; the first row is
        ``("", "ours", "TetGen", ...)``): for tests and scripts."""
        t = self.table
        rows = [("",) + tuple(t.horizontalHeaderItem(c).text() for c in range(t.columnCount()))]
        for row in range(t.rowCount()):
            cells = [t.item(row, c) for c in range(t.columnCount())]
            rows.append((t.verticalHeaderItem(row).text(),) +
                        tuple(c.text() if c is not None else "" for c in cells))
        return rows


def _as_bsptet_error(error):
    """``error`` itself if it is one of ours, else an InternalError that names it."""
    if isinstance(error, BspTetError):
        return error

    return InternalError("unexpected %s: %s" % (type(error).__name__, error))
