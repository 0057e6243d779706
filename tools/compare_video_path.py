#!/usr/bin/env python3
"""Video path vs session path on a demo session (issue 17, "checked from outside").

The demo's camera converted to a plain video (analyze VIDEO: one camera, approximate intrinsics)
and the session itself (analyze SESSION: three calibrated cameras) are compared with the demo's
truth.jsonl: face recall (ticks where the face is visible in that camera) and the median angle
between the head-gaze direction and the true one (degrees; the video's camera-frame directions are
rotated into the world with the camera's calibration, which only rotates, so the error is the
camera-frame error).

  python3 tools/compare_video_path.py SESSION_DIR SESSION_ANALYSIS VIDEO_ANALYSIS [CAMERA [world]]

"world": the video was analysed with --calibration CAMERA.yaml, whose extrinsics already put its
results in the session's world (no rotation here).
"""
import json
import math
import re
import sys


def records(path, primitive):
    out = {}
    with open(path) as f:
        for line in f:
            r = json.loads(line)
            if r["primitive"] == primitive:
                out[r["stamp_ns"]] = r
    return out


def camera_rotation(yaml_path):
    text = open(yaml_path).read()
    block = text[text.index("camera_from_world_R"):]
    data = re.search(r"data:\s*\[([^\]]*)\]", block, re.S).group(1)
    v = [float(x) for x in data.replace("\n", " ").split(",")]
    return [v[0:3], v[3:6], v[6:9]]


def angle_deg(a, b):
    na = math.sqrt(sum(x * x for x in a))
    nb = math.sqrt(sum(x * x for x in b))
    c = sum(x * y for x, y in zip(a, b)) / (na * nb)
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def median(v):
    v = sorted(v)
    return v[len(v) // 2] if v else float("nan")


def main():
    session, session_out, video_out = sys.argv[1:4]
    camera = sys.argv[4] if len(sys.argv) > 4 else "camera_middle"
    video_in_world = len(sys.argv) > 5 and sys.argv[5] == "world"
    R = camera_rotation(f"{session}/calib/{camera}.yaml")
    truth = {}
    with open(f"{session}/truth.jsonl") as f:
        for line in f:
            t = json.loads(line)
            if t.get("type") == "face":
                truth[t["stamp_ns"]] = t
    result = {}
    for name, out, rotate in (("session", session_out, False), ("video", video_out, not video_in_world)):
        faces = records(f"{out}/primitives.jsonl", "getFaces")
        heads = records(f"{out}/primitives.jsonl", "getHeadGaze")
        visible = found = 0
        errors = []
        for stamp, t in truth.items():
            cam = t["cameras"].get(camera, {})
            if not cam.get("visible"):
                continue
            visible += 1
            r = faces.get(stamp)
            if r and r["status"] == "ok":
                found += 1
            h = heads.get(stamp)
            if h and h["status"] == "ok":
                d = h["value"]["direction"]
                if rotate:  # camera frame -> world: R^T d
                    d = [sum(R[i][j] * d[i] for i in range(3)) for j in range(3)]
                errors.append(angle_deg(d, t["head_gaze_dir"]))
        result[name] = {"face_recall": found / visible if visible else float("nan"),
                        "head_pose_median_deg": median(errors), "ticks": visible}
    s, v = result["session"], result["video"]
    result["video_vs_session"] = {
        "face_recall_ratio": v["face_recall"] / s["face_recall"],
        "head_pose_error_ratio": v["head_pose_median_deg"] / s["head_pose_median_deg"]}
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
