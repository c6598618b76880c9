"""Stage verify: finish the integrated pose (V_C onto its targets) and check the repaired pose.

Two finishes (``--finish``). ``contact``: the contact solver (IPC) moves the integrated pose, V_C onto
its targets and the rest toward its goal, and no intersection that the reference does not have can
form (``posefix.verify.sequence.finish_pose``). ``snap``: puts the constrained vertices exactly on
their targets (blending the fit's residual into the rest), replaces regions by the target where
integration could not reach it (S0 Fig. 9) and untangles new intersections
(``posefix.verify.sequence.repair_pose``). Both then count intersecting faces of reference, target
and repaired pose ("new": intersecting in the repaired pose, not in the reference) and measure the
deviation from the target over V_C and the rest. Stage ``export`` writes the mesh.
"""

import json
from dataclasses import asdict

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.mesh.contact_solver import ContactSettings
from posefix.mesh.geometry import unit_scale
from posefix.io.artifacts import carried_metrics, read_artifact, write_artifact
from posefix.io.keyframes import read_keyframes
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.workflow.timings import Timings
from posefix.verify.contact_finish import FinishSettings
from posefix.verify.sequence import RepairSettings, finish_settings, finished_pose
from posefix.verify.state import RepairProblem
from posefix.spacetime.classification import split_frames


def build_parser():
    settings = [(RepairSettings, "finish (config verify)"), (FinishSettings, "contact finish (config verify)"),
                (ContactSettings, "contact solver (config contact)")]
    return stage_parser("verify", __doc__, settings,
                        keyframes="keyframes.h5 of the pose (reference, target, faces)",
                        classify="classify.h5 of the pose (V_C, reference intersections)",
                        integrate="integrate.h5 of the pose", fit="fit.h5 of the pose (eps)",
                        out="verify.h5 to write")


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        kf, kattrs = read_keyframes(args.keyframes, ["reference", "target", "faces", "frames"])
        cl, _ = read_artifact(args.classify, "classify", ["mask", "pairs", "pair_offsets"])
        it, iattrs = read_artifact(args.integrate, "integrate", ["positions", "samples"])
        _, fattrs = read_artifact(args.fit, "fit", [])
    unit = unit_scale(kf["reference"])  # the working unit: a library at 1e-30 or 1e+30 repairs as at 1
    problem = RepairProblem.build(unit * kf["reference"], unit * kf["target"], kf["faces"], cl["mask"],
                                  split_frames(cl["pairs"], cl["pair_offsets"]))
    result, params = _finish(args, problem, (it, kf["frames"], unit), fattrs)
    timings.update(result.seconds)
    _say_what_was_left(json.loads(kattrs["inputs"])[-1], result.metrics, log)
    write_artifact(
        args.out, "verify",
        {"repaired": result.X / unit, "deviation": result.deviation, "replaced": result.replaced,
         "new_faces": result.new, "pairs": result.pairs},
        params=params,
        inputs=[args.keyframes, args.classify, args.integrate, args.fit], timings=timings,
        metrics=result.metrics | carried_metrics(iattrs["metrics"], "integrate"), docs=dataset_docs("verify"))


def _say_what_was_left(target, metrics, log):
    """A warning naming the pose file when the repair left something: new intersecting faces, vertices the snap
    finish took from the target (pass-through: the target's intersections with them), or a contact finish that
    fell back to the path lines."""
    left = []
    if metrics["repaired_new"]:
        left.append(f"{metrics['repaired_new']} new intersecting faces remain")
    if metrics.get("fallback_pass_through"):
        left.append(f"{metrics['fallback_pass_through']} vertices are the target's (pass-through: key frames pass "
                    "through each other there)")
    if metrics.get("contact_reverted"):
        left.append("the contact finish fell back to the integrated path (a step it could not bound)")
    if left:
        log.warning("%s: %s; see the report's pose page", target, "; ".join(left))


def _finish(args, problem, integrated, fit_attrs):
    """(RepairResult, params) of the finish ``args.finish`` of the integrated pose, in the working unit;
    ``integrated``: (integrate.h5's arrays, the key frames (K, n, 3), the working unit (lengths times it: ``problem``'s
    are))."""
    integrated, frames, unit = integrated
    d = unit * float(fit_attrs["metrics"]["bbox_diagonal"])
    eps = json.loads(fit_attrs["config"])["eps_rel"] * d
    settings = finish_settings(vars(args))
    result = finished_pose(problem, (unit * integrated["samples"], unit * frames), d, settings,
                           (eps, float(fit_attrs["metrics"]["max_error_rel"])))
    repair, finish, contact = map(asdict, settings)
    return result, repair if args.finish == "snap" else {"finish": "contact"} | finish | contact


if __name__ == "__main__":
    run_stage(build_parser(), main)
