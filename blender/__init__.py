"""posefix in Blender: *Repair shape keys* repairs the self-intersections of the active mesh's shape keys.

The basis is the reference and every other shape key (or the ones named) a pose. The repair runs in the posefix
environment (the preferences name its Python) as a background process, so Blender stays live: the status bar shows
the progress, and *Cancel* or Esc stops it and changes nothing. The repaired keys go back as new keys
``<name>.repaired`` or in place, each keeping its relative key, value, range, vertex group and mute. The panel
(Properties > Object Data > posefix) lists per key its status, intersecting faces before and after and distorted
faces, and switches between a key and its repair. Bad input (no shape keys, a non-mesh object, a key with another
vertex count, modifiers that change the topology) is one line in Blender's report, and nothing changes.
"""

import json
import os

import bpy

from . import job as jobs
from . import shape_keys

_RUNNING = {}
"""The job running per object name (one at a time per object)."""


class PosefixPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    python: bpy.props.StringProperty(
        name="posefix Python", subtype="FILE_PATH",
        description="The Python of the environment where posefix is installed (empty: $POSEFIX_PYTHON, else the "
                    "posefix command's)")
    cores: bpy.props.IntProperty(name="Cores", default=2, min=1, description="Shape keys repaired at once")

    def draw(self, context):
        self.layout.prop(self, "python")
        self.layout.prop(self, "cores")


def _preferences(context):
    """The add-on's preferences, or None when it is not installed as an add-on (loaded by a script)."""
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


class POSEFIX_OT_repair_shape_keys(bpy.types.Operator):
    """Repair the self-intersections of the active mesh's shape keys (the basis is the reference)"""

    bl_idname = "posefix.repair_shape_keys"
    bl_label = "Repair shape keys"
    bl_options = {"REGISTER", "UNDO"}

    in_place: bpy.props.BoolProperty(name="In place", default=False,
                                     description="Replace each key's positions (else write <name>.repaired keys)")
    keys: bpy.props.StringProperty(name="Keys", default="",
                                   description="The keys to repair, comma-separated (empty: every key but the basis)")

    def _start(self, context):
        """Start the job of the active object, or report why not: the job, or None."""
        obj, names = context.active_object, [n.strip() for n in self.keys.split(",") if n.strip()]
        said = shape_keys.problem(obj, names, context.evaluated_depsgraph_get())
        preferences = _preferences(context)
        python = jobs.posefix_python(preferences.python if preferences else "")
        if not said and python is None:
            said = "posefix not found: set the posefix Python in the add-on's preferences (or $POSEFIX_PYTHON)"
        elif not said and not os.path.isfile(python):
            said = f"posefix Python {python}: no such file (set the posefix Python in the add-on's preferences)"
        if said:
            self.report({"ERROR"}, said)
            return None
        self._keys, self._object = shape_keys.pose_keys(obj, names), obj.name
        return jobs.Job(python, shape_keys.job_arrays(obj, self._keys), preferences.cores if preferences else 2)

    def execute(self, context):  # a script's call (and the headless tests): the job runs to its end
        job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        failure = jobs.wait(job)
        return self._finish(context, job, failure)

    def invoke(self, context, event):
        job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        self._job = job
        _RUNNING[self._object] = self
        self._timer = context.window_manager.event_timer_add(0.25, window=context.window)
        context.window_manager.modal_handler_add(self)
        context.workspace.status_text_set(f"posefix: repairing {len(self._keys)} shape keys (Esc: cancel)")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" or getattr(self, "_cancelled", False):
            self._job.cancel()
            self._stop(context)
            self.report({"WARNING"}, "posefix: cancelled; no shape key changed")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if not self._job.done():
            done = len(self._job.finished())
            context.workspace.status_text_set(f"posefix: {done} of {len(self._keys)} shape keys repaired "
                                              "(Esc: cancel)")
            return {"RUNNING_MODAL"}
        self._stop(context)
        return self._finish(context, self._job, self._job.failure())

    def _stop(self, context):
        context.window_manager.event_timer_remove(self._timer)
        context.workspace.status_text_set(None)
        _RUNNING.pop(self._object, None)

    def _finish(self, context, job, failure):
        """Write the repaired keys back (none when the job failed) and report."""
        try:
            if failure:
                self.report({"ERROR"}, failure.removeprefix("posefix: error: "))
                return {"CANCELLED"}
            obj, lines = bpy.data.objects[self._object], job.finished()
            for index, (key, line) in enumerate(zip(self._keys, lines)):
                if line["status"] != "error":
                    line["repaired"] = shape_keys.write_key(obj, key, job.repaired(index), self.in_place).name
            obj[shape_keys.RESULTS] = json.dumps([{k: v for k, v in line.items() if k not in ("done", "total")}
                                                  for line in lines])
            counts = {s: sum(line["status"] == s for line in lines) for s in ("ok", "fallback", "check", "error")}
            self.report({"INFO"}, "posefix: " + ", ".join(f"{n} {s}" for s, n in counts.items() if n))
            return {"FINISHED"}
        finally:
            job.close()


class POSEFIX_OT_cancel_repair(bpy.types.Operator):
    """Stop the repair of the active object's shape keys; no key changes"""

    bl_idname = "posefix.cancel_repair"
    bl_label = "Cancel"

    def execute(self, context):
        running = _RUNNING.get(context.active_object.name) if context.active_object else None
        if running:
            running._cancelled = True
        return {"FINISHED"}


class POSEFIX_OT_show_shape_key(bpy.types.Operator):
    """Show this shape key alone (the others muted in the viewport)"""

    bl_idname = "posefix.show_shape_key"
    bl_label = "Show shape key"

    name: bpy.props.StringProperty()

    def execute(self, context):
        obj = context.active_object
        index = obj.data.shape_keys.key_blocks.find(self.name) if obj and obj.data.shape_keys else -1
        if index < 0:
            self.report({"ERROR"}, f"no shape key named '{self.name}'")
            return {"CANCELLED"}
        obj.active_shape_key_index, obj.show_only_shape_key = index, True
        return {"FINISHED"}


def result_rows(obj):
    """The panel's rows for ``obj``: its last repair's lines (dicts), or []."""
    try:
        return json.loads(obj.get(shape_keys.RESULTS, "[]"))
    except (TypeError, ValueError):
        return []


class POSEFIX_PT_shape_keys(bpy.types.Panel):
    bl_label = "posefix"
    bl_space_type, bl_region_type, bl_context = "PROPERTIES", "WINDOW", "data"

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "MESH"

    def draw(self, context):
        layout, obj = self.layout, context.active_object
        if obj.name in _RUNNING:
            layout.label(text="Repairing shape keys ...")
            layout.operator(POSEFIX_OT_cancel_repair.bl_idname, icon="CANCEL")
            return
        row = layout.row()
        row.operator(POSEFIX_OT_repair_shape_keys.bl_idname, text="Repair as new keys").in_place = False
        row.operator(POSEFIX_OT_repair_shape_keys.bl_idname, text="Repair in place").in_place = True
        for line in result_rows(obj):
            _draw_row(layout.box(), line)


def _draw_row(box, line):
    """One key's line of the panel: status, intersecting faces target -> repaired (new), distorted faces; buttons
    that show the key and its repair."""
    header = box.row()
    header.label(text=f"{line['name']}: {line['status']}", icon="CHECKMARK" if line["status"] == "ok" else "ERROR")
    header.operator(POSEFIX_OT_show_shape_key.bl_idname, text="Key").name = line["name"]
    if "repaired" in line:
        header.operator(POSEFIX_OT_show_shape_key.bl_idname, text="Repair").name = line["repaired"]
        faces = line["intersecting_faces"]
        box.label(text=f"intersecting faces {faces['target']} -> {faces['repaired']} ({faces['repaired_new']} new); "
                       f"distorted faces {line['distorted_faces']}")
    if line.get("reason"):
        box.label(text=line["reason"])


CLASSES = (PosefixPreferences, POSEFIX_OT_repair_shape_keys, POSEFIX_OT_cancel_repair, POSEFIX_OT_show_shape_key,
           POSEFIX_PT_shape_keys)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
