# SPDX-License-Identifier: LGPL-2.1-or-later
"""Offscreen GUI test: FreeCAD's real GUI (``QT_QPA_PLATFORM=offscreen freecad ...``) with the
checkout installed as a Mod in a throw-away HOME (so the user's configuration is never touched).

tests/gui_offscreen_session.py runs inside FreeCAD and records facts; this test asserts them: the
command in FEM's toolbar and Mesh menu and in our workbench, the command creating the object in
the active analysis and opening the task panel, the task panel meshing in a worker process with
stats and the comparison at the same size, fitting the combo view, Stop killing the worker and keeping the previous mesh, a failed run
keeping the previous mesh, save/reload with the mesh, the preferences page.
About 10-20 s.
"""

import json
import os
import shutil
import subprocess

import pytest

from FemBspTet.gui.task_panel import compact_count

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SESSION = os.path.join(ROOT, "tests", "gui_offscreen_session.py")

if shutil.which("freecad") is None or shutil.which("freecadcmd") is None:
    # both come with freecad-python3, a declared dependency: missing is a failure, not a skip
    pytest.fail("freecad/freecadcmd (Debian package freecad-python3) are missing: run "
                "scripts/setup.sh", pytrace=False)


@pytest.fixture(scope="module")
def facts(tmp_path_factory):
    home = tmp_path_factory.mktemp("home")
    mods = home / ".local" / "share" / "FreeCAD" / "Mod"
    mods.mkdir(parents=True)
    os.symlink(ROOT, mods / "FemBspTet")  # installed the way the README says
    env = dict(os.environ, HOME=str(home), QT_QPA_PLATFORM="offscreen")
    env.pop("PYTHONPATH", None)  # the addon must load as a Mod, not from our path
    # The Start page's QtWebEngine aborts offscreen: start in the Part workbench instead.
    # FreeCAD 1.x's notification area deadlocks offscreen (its pop-up's raise() makes Qt warn,
    # and the warning comes back into the notification area): notifications off.
    subprocess.run(["freecadcmd", "-c",
                    "import FreeCAD; FreeCAD.ParamGet('User parameter:BaseApp/Preferences/"
                    "General').SetString('AutoloadModule', 'PartWorkbench'); "
                    "g = FreeCAD.ParamGet('User parameter:BaseApp/Preferences/NotificationArea'); "
                    "g.SetBool('NotificationAreaEnabled', False); "
                    "g.SetBool('NonIntrusiveNotificationsEnabled', False)"],
                   env=env, check=True, capture_output=True, timeout=120)
    out = home / "facts.json"
    env["FEMBSPTET_GUI_OUT"] = str(out)
    if os.environ.get("FEMBSPTET_GUI_SCREENSHOT"):
        env["FEMBSPTET_GUI_SCREENSHOT"] = os.environ["FEMBSPTET_GUI_SCREENSHOT"]
    proc = subprocess.run(["freecad", SESSION], env=env, cwd=str(home), stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, timeout=600)
    assert out.exists(), "the GUI session wrote nothing: %s" % proc.stdout.decode()[-3000:]
    with open(out) as f:
        data = json.load(f)
    data["_log"] = proc.stdout.decode(errors="replace")
    return data


def test_session_ran_every_step(facts):
    assert facts["gui_up"] is True
    assert facts["errors"] == []


def test_command_in_fem_toolbar_menu_and_own_workbench(facts):
    assert facts["workbench_registered"] and facts["command_registered"]
    if facts["workbench_manipulators"]:  # FreeCAD 1.x: among FEM's meshers, just before Gmsh
        tools = facts["fem_toolbar_with_gmsh"]
        assert tools.index("FEM_MeshBspTetFromShape") == tools.index("FEM_MeshGmshFromShape") - 1
    else:  # FreeCAD 0.20/0.21: a toolbar of its own in FEM
        assert facts["bsptet_toolbar_in_fem"] == ["FEM_MeshBspTetFromShape"]
    entries = facts["fem_mesh_menu_entries"]
    assert "FEM_MeshBspTetFromShape" in entries
    assert entries.index("FEM_MeshBspTetFromShape") == entries.index("FEM_MeshGmshFromShape") + 1
    assert facts["own_workbench_toolbar"] == ["FEM_MeshBspTetFromShape"]
    assert facts["command_active_with_selection"] is True
    assert facts["command_active_without_selection"] is False
    assert facts["menu_entry_enabled_without_selection"] is False
    assert facts["objects_after_command_without_selection"] == \
        facts["objects_before_command_without_selection"]


def test_command_creates_object_in_analysis_and_opens_panel(facts):
    # FreeCAD 1.x: a shape-based FEM mesh object (link Shape); 0.20/0.21: a FEM mesh object
    assert facts["object_type"] in ("Fem::FemMeshShapeBaseObjectPython", "Fem::FemMeshObjectPython")
    assert facts["object_type"] == facts["expected_object_type"]
    assert facts["proxy_type"] == "Fem::FemMeshBspTet"
    assert facts["part_link"] == "Block"
    assert facts["view_provider"] == "VPMeshBspTet"
    assert facts["in_analysis"] is True
    assert facts["task_dialog_open_after_command"] is True
    # created by the Python line doCommand ran in FreeCAD's console namespace (journaled)
    assert facts["created_through_doCommand"] is True


def test_task_panel_meshes_in_a_worker_and_shows_stats(facts):
    assert facts["panel_is_ours"] is True
    assert facts["apply_started"] is True
    assert facts["gui_responsive_while_meshing"] is True  # Mesh returned while it ran
    assert facts["panel_finished"] is True and facts["panel_error"] is None
    assert facts["panel_progress"] == 1000
    n, t = facts["nodes_after_mesh"], facts["tets_after_mesh"]
    assert n > 0 and t > 0
    assert facts["result_nodes_property"] == n
    assert facts["mesh_status"] == "meshed: %d nodes, %d tet4" % (n, t)
    assert facts["panel_status"] == facts["mesh_status"]
    assert facts["panel_stats"].startswith("%d nodes, %d tetrahedra" % (n, t))
    # the comparison at the same size: one row per mesher, ours first, the same figures as the
    # object's properties; TetGen, Gmsh and Netgen are declared dependencies: all there
    head, *cells = facts["panel_table"]
    assert tuple(head) == ("", "ours", "TetGen", "Gmsh", "Netgen")
    table = {row[0]: row[1:] for row in cells}  # figure -> one cell per mesher
    assert list(table) == ["nodes", "tets", "min°", "med°", "s"]
    rows = facts["comparison_rows"]
    assert [r["mesher"] for r in rows] == ["FemBspTet", "TetGen", "Gmsh", "Netgen"]
    assert (table["nodes"][0], table["tets"][0]) == (str(n), str(t))  # small: written out
    for k, row in enumerate(rows):
        assert row["status"] == "ok", row
        assert row["tets"] > 0 and table["tets"][k] == compact_count(row["tets"])
        assert float(table["min°"][k]) == pytest.approx(row["min_dihedral_deg"], abs=0.05)
        assert float(table["med°"][k]) == pytest.approx(row["median_tet_min_dihedral_deg"],
                                                       abs=0.05)
    assert rows[1]["command"].startswith("tetgen -pq1.414a")
    # faces and groups per CAD face by default: a face group and a node group per face
    assert facts["face_count_after_mesh"] > 0
    assert facts["group_count_after_mesh"] == 2 * facts["cad_faces"]


def test_task_panel_fits_the_combo_view(facts):
    """FreeCAD's combo view as a new user's FreeCAD opens it (offscreen: a 244-pixel task view at
    a 12-point font): the whole task view fits it, with OK, Cancel and every control of ours
    visible, every figure of the comparison shown, no column cut."""
    assert facts["panel_in_scroll_area"] is True
    assert facts["task_view_hscroll"] == 0, facts["task_view_parts_min_width"]
    assert facts["panel_min_width"] <= facts["task_view_width"]
    assert facts["dialog_buttons"] == ["Cancel", "OK"] and facts["dialog_buttons_inside"] is True
    assert facts["panel_buttons"] == ["Mesh", "Stop"]
    assert facts["table_fits"] is True and facts["table_columns_fit"] is True


def test_task_panel_keeps_the_size_exact_and_reopens_with_results(facts):
    assert facts["size_after_store"] == 10.123456789
    # reopened after the failed run: its message, the mesh before it, no percentage anywhere
    assert facts["mesh_status_at_reopen"].startswith("failed: ")
    assert facts["reopened_status"].startswith(facts["mesh_status_at_reopen"])
    assert facts["reopened_status"].endswith("The mesh shown is the one before.")
    assert facts["reopened_progress"] == 0
    assert facts["reopened_progress_text_visible"] is False
    assert facts["reopened_table_rows"] == 5  # every figure of every mesher


def test_stop_kills_the_worker_and_keeps_the_mesh(facts):
    assert facts["restart_started"] is True
    assert facts["running_before_stop"] is True
    assert facts["worker_ended_after_stop"] is True
    assert facts["running_after_stop"] is False
    assert facts["mesh_kept_after_stop"] is True
    assert "previous mesh is kept" in facts["status_after_stop"]


def test_failure_keeps_the_mesh_and_says_why(facts):
    assert "holds no solid (1 shell(s), 5 face(s))" in facts["failure_error"]
    assert facts["failure_status_property"].startswith("failed: ")
    assert facts["mesh_kept_after_failure"] is True
    assert "meshing MeshBspTet failed" in facts["_log"]


def test_ok_and_double_click(facts):
    assert facts["ok_closes"] is True
    assert facts["dialog_open_after_ok"] is False
    assert facts["dialog_open_after_double_click"] is True


def test_save_and_reload_with_the_mesh(facts):
    assert facts["gui_document_has_vp_module"] is True
    assert facts["reloaded_nodes_equal"] is True
    assert facts["reloaded_proxy_type"] == "Fem::FemMeshBspTet"
    assert facts["reloaded_view_provider"] == "VPMeshBspTet"
    assert facts["reloaded_part"] == "Block"


def test_preferences_page_loads(facts):
    assert facts["prefs_combobox_class"] == "Gui::PrefComboBox"
    assert facts["prefs_checkboxes"] == ["ck_compare_peers", "ck_face_groups"]
