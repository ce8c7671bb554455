#!/usr/bin/python3
"""Tessera's one-process CPU ray caster against VTK 9's vtkFixedPointVolumeRayCastMapper.

Same case on both sides: a scene with a generated volume (default: the built-in hollow shell;
--scene takes any scene file whose volume is a cubic generator, with its transfer function,
camera, shading and light), the volume dumped exactly by tessera-dump-volume, a 1024x1024
image, a one-voxel step (Tessera's L0 = 1/256 of the unit box = one voxel), 2 threads.
Shading maps to VTK's ShadeOn with the same ambient/diffuse/specular/specular power, under
VTK's headlight or, for a scene `light`, one directional scene light from that direction.
A scene's `blend: maximum` maps to VTK's SetBlendModeToMaximumIntensity (its colour map must
reach opacity 1, where Tessera's scaling of a projection's opacity leaves it as VTK takes it).
Each round runs, back to back: VTK (a fresh process: warm-up render, then --frames timed
renders), tessera-render with empty-space skipping, tessera-render with --no-skip. A round's
figure is each side's best frame (wall) and CPU ms per frame (all threads; Tessera's from the
CPU difference between a run of frames+1 and a run of 1 frame); the summary gives min and
median over rounds.

Needs Debian's python3-vtk9, python3-numpy and python3-yaml (use /usr/bin/python3, not a pyenv one) and an
X display for VTK's offscreen window (re-runs itself under xvfb-run when DISPLAY is unset).
Usage: tests/bench/vtk_compare.py [--build-dir build] [--scene scenes/shaded-lobb.yaml] [--no-shading]
                                  [--rounds 5] [--frames 5]
"""
import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# Tessera's defaultScene() (common/scene.cpp): scalar, r, g, b, alpha per L0 = 1/256.
DEFAULT_TF = [(0.00, 0.0, 0.0, 0.0, 0.0),
      (0.05, 1.0, 0.45, 0.1, 0.0),
      (0.50, 1.0, 0.55, 0.15, 0.06),
      (0.70, 1.0, 0.8, 0.5, 0.2),
      (1.00, 1.0, 1.0, 0.9, 0.9)]
L0 = 1.0 / 256  # Tessera's reference length and default step (common/transfer_function.h)
DEFAULT_CAMERA = {"eye": [0.0, 0.6, 2.2], "target": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fov": 30.0}
SHADING_DEFAULTS = {"ambient": 0.1, "diffuse": 0.7, "specular": 0.2, "shininess": 10}  # VTK's, as Tessera's


def load_case(args):
    """The compared case: generator, transfer function, camera, shading and light, from
    --scene (a generator scene file) or the built-in default scene."""
    case = {"generator": args.generator, "volume_size": args.volume_size, "tf": DEFAULT_TF,
            "camera": DEFAULT_CAMERA, "shading": None, "light": None, "blend": "composite"}
    if not args.scene:
        return case
    import yaml
    with open(args.scene) as f:
        sc = yaml.safe_load(f)
    gen = (sc.get("volume") or {}).get("generator")
    if not gen or "spacing" in gen:
        sys.exit(f"vtk_compare: {args.scene}: needs a volume generator with unit spacing (a cube)")
    if "crop" in sc:  # VTK's cropping planes would need Tessera's voxel rounding: not compared
        sys.exit(f"vtk_compare: {args.scene}: a cropped scene is not compared; leave out `crop`")
    if "window" in sc:  # the comparison gives VTK the scene's own points
        sys.exit(f"vtk_compare: {args.scene}: a scene with a colour `window` is not compared; leave it out")
    case["generator"] = gen["name"]
    if args.volume_size_given is None:
        case["volume_size"] = gen.get("size", 256)
    tf = sc.get("transfer_function")
    if tf is not None:
        if not isinstance(tf, list):
            sys.exit(f"vtk_compare: {args.scene}: give the transfer function as points, not a preset")
        case["tf"] = [tuple(p) for p in tf]
    cam = sc.get("camera")
    if cam:
        if cam.get("orthographic"):
            sys.exit(f"vtk_compare: {args.scene}: perspective cameras only")
        case["camera"] = {"eye": cam["eye"], "target": cam["target"], "up": cam.get("up", [0, 1, 0]),
                          "fov": cam.get("fov", 30)}
    sh = sc.get("shading")
    if sh and not args.no_shading:
        case["shading"] = dict(SHADING_DEFAULTS, **(sh if isinstance(sh, dict) else {}))
    case["light"] = sc.get("light")
    case["blend"] = sc.get("blend", "composite")
    if case["blend"] not in ("composite", "maximum"):
        sys.exit(f"vtk_compare: {args.scene}: blend: {case['blend']} is not compared (composite and maximum are)")
    if case["blend"] == "maximum" and max(p[4] for p in case["tf"]) != 1:
        sys.exit(f"vtk_compare: {args.scene}: for blend: maximum give the transfer function an opacity of 1 at its "
                 f"top (Tessera scales a projection's opacity so that its largest is 1, VTK does not)")
    return case


def require_modules():
    try:
        import numpy  # noqa: F401
        import vtkmodules  # noqa: F401
    except ImportError as e:
        sys.exit(f"vtk_compare: {e}. Install Debian's packages: apt-get install -y python3-vtk9 python3-numpy, "
                 f"and run with /usr/bin/python3 (this is {sys.executable}).")


def vtk_worker(args):
    """Renders with VTK in this process; prints one JSON line with per-frame times."""
    import numpy as np
    import vtk
    from vtk.util import numpy_support

    with open(args.case) as f:
        case = json.load(f)
    n = case["volume_size"]
    vol = np.fromfile(args.raw, dtype="<f4")
    if vol.size != n ** 3:
        sys.exit(f"vtk_compare: {args.raw} has {vol.size} values, expected {n}^3")
    vtk.vtkMultiThreader.SetGlobalMaximumNumberOfThreads(args.threads)
    vtk.vtkMultiThreader.SetGlobalDefaultNumberOfThreads(args.threads)

    # Tessera's unit box: largest extent 1, centred at 0, voxel i at the centre of cell i,
    # index x fastest (same order as VTK point data).
    h = 1.0 / n
    img = vtk.vtkImageData()
    img.SetDimensions(n, n, n)
    img.SetSpacing(h, h, h)
    img.SetOrigin(-0.5 + 0.5 * h, -0.5 + 0.5 * h, -0.5 + 0.5 * h)
    arr = numpy_support.numpy_to_vtk(vol, deep=True, array_type=vtk.VTK_FLOAT)
    arr.SetName("scalars")
    img.GetPointData().SetScalars(arr)

    color = vtk.vtkColorTransferFunction()
    opacity = vtk.vtkPiecewiseFunction()
    for s, r, g, b, a in case["tf"]:
        color.AddRGBPoint(s, r, g, b)
        opacity.AddPoint(s, a)
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(color)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(L0)  # alpha per L0, as Tessera's (one voxel at 256^3)
    prop.SetInterpolationTypeToLinear()   # Tessera: trilinear, post-classification
    sh = case["shading"]
    if sh:  # Tessera's shading: the same coefficients (VTK lights two-sided by default)
        prop.ShadeOn()
        prop.SetAmbient(sh["ambient"])
        prop.SetDiffuse(sh["diffuse"])
        prop.SetSpecular(sh["specular"])
        prop.SetSpecularPower(sh["shininess"])
    else:
        prop.ShadeOff()                   # Tessera: emission-absorption, no shading

    mapper = vtk.vtkFixedPointVolumeRayCastMapper()
    mapper.SetInputData(img)
    mapper.SetSampleDistance(L0)  # Tessera's default step (one voxel at 256^3)
    mapper.AutoAdjustSampleDistancesOff()
    mapper.LockSampleDistanceToInputSpacingOff()
    mapper.SetImageSampleDistance(1.0)  # one ray per pixel
    mapper.SetIntermixIntersectingGeometry(0)  # no geometry in the scene: skip the depth read
    mapper.SetNumberOfThreads(args.threads)
    if case["blend"] == "maximum":  # Tessera's blend: maximum; VTK maps the largest value as Tessera does
        mapper.SetBlendModeToMaximumIntensity()
    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)

    ren = vtk.vtkRenderer()
    ren.SetBackground(0, 0, 0)
    ren.AddVolume(volume)
    if case["light"]:  # else VTK's automatic headlight, as Tessera's
        light = vtk.vtkLight()
        light.SetLightTypeToSceneLight()
        light.SetPositional(False)
        light.SetPosition(*case["light"])
        light.SetFocalPoint(0, 0, 0)
        ren.AddLight(light)
    c = case["camera"]
    cam = ren.GetActiveCamera()
    cam.ParallelProjectionOff()
    cam.SetPosition(*c["eye"])
    cam.SetFocalPoint(*c["target"])
    cam.SetViewUp(*c["up"])
    cam.SetViewAngle(c["fov"])  # vertical, like Tessera's fov
    cam.SetClippingRange(0.05, 10.0)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetMultiSamples(0)
    win.SetSize(args.size, args.size)
    win.AddRenderer(ren)

    t0 = time.perf_counter()
    win.Render()  # warm-up: builds VTK's scalar tables and min-max space-leaping volume
    warm_ms = (time.perf_counter() - t0) * 1e3
    wall, mapper_ms, cpu = [], [], []
    for _ in range(args.frames):
        cam.Modified()
        t0, c0 = time.perf_counter(), time.process_time()
        win.Render()
        wall.append((time.perf_counter() - t0) * 1e3)
        cpu.append((time.process_time() - c0) * 1e3)  # all threads of this process
        mapper_ms.append(mapper.GetTimeToDraw() * 1e3)
    if args.png:
        grab = vtk.vtkWindowToImageFilter()
        grab.SetInput(win)
        grab.ReadFrontBufferOff()
        grab.SetInputBufferTypeToRGB()
        grab.Update()
        writer = vtk.vtkPNGWriter()
        writer.SetFileName(args.png)
        writer.SetInputConnection(grab.GetOutputPort())
        writer.Write()
    print(json.dumps({"vtk": vtk.vtkVersion.GetVTKVersion(), "threads": mapper.GetNumberOfThreads(),
                      "warm_ms": warm_ms, "wall_ms": wall, "cpu_ms": cpu, "mapper_ms": mapper_ms}))


def scene_yaml(case, size):
    """The case as a Tessera scene file."""
    rows = "\n".join(f"  - [{s}, {r}, {g}, {b}, {a}]" for s, r, g, b, a in case["tf"])
    c, sh = case["camera"], case["shading"]
    text = (f"volume:\n  generator: {{name: {case['generator']}, size: {case['volume_size']}, seed: 1}}\n"
            f"transfer_function:\n{rows}\n"
            f"camera: {{eye: {list(c['eye'])}, target: {list(c['target'])}, up: {list(c['up'])}, fov: {c['fov']}}}\n"
            f"image: [{size}, {size}]\nquality: default\n")
    if sh:
        text += "shading: {" + ", ".join(f"{k}: {v}" for k, v in sh.items()) + "}\n"
    if case["light"]:
        text += f"light: {list(case['light'])}\n"
    if case["blend"] != "composite":
        text += f"blend: {case['blend']}\n"
    return text


def children_cpu_s():
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def run_tessera(args, tool, scene, png, no_skip, repeat):
    """Returns (best wall ms of `repeat` frames, CPU seconds of the whole process, command)."""
    cmd = [tool] + ([scene] if scene else []) + [
        "--stats", "--repeat", str(repeat), "--threads", str(args.threads),
        "--image", f"{args.size}x{args.size}", "--background", "0,0,0", "-o", png]
    if no_skip:
        cmd.append("--no-skip")
    cpu0 = children_cpu_s()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    cpu = children_cpu_s() - cpu0
    for tok in out.split():
        if tok.startswith("time_ms="):
            return float(tok.split("=")[1]), cpu, " ".join(cmd)
    sys.exit(f"vtk_compare: no time_ms in tessera-render output:\n{out}")


def tessera_frame(args, tool, scene, png, no_skip):
    """Best wall ms over --frames, and CPU ms per frame as the CPU difference between a run of
    --frames + 1 frames and a run of 1 frame (cancels volume generation and start-up)."""
    wall, cpu_n, cmd = run_tessera(args, tool, scene, png, no_skip, args.frames + 1)
    _, cpu_1, _ = run_tessera(args, tool, scene, png, no_skip, 1)
    return wall, (cpu_n - cpu_1) / args.frames * 1e3, cmd


def run_vtk(args, raw, case_json, png):
    cmd = [sys.executable, os.path.abspath(__file__), "--vtk-worker", "--raw", raw, "--case", case_json,
           "--image", str(args.size),
           "--frames", str(args.frames), "--threads", str(args.threads)]
    if png:
        cmd += ["--png", png]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def compare_images(a_png, b_png):
    """Differences between the two 8-bit images (RGB, both over black)."""
    import numpy as np
    import vtk
    from vtk.util import numpy_support

    def load(p):
        r = vtk.vtkPNGReader()
        r.SetFileName(p)
        r.Update()
        o = r.GetOutput()
        w, h, _ = o.GetDimensions()
        a = numpy_support.vtk_to_numpy(o.GetPointData().GetScalars()).reshape(h, w, -1)
        return a[:, :, :3].astype(np.float64)

    a, b = load(a_png), load(b_png)
    d = np.abs(a - b)

    def footprint(x):
        ys, xs = np.nonzero(x.max(axis=2) > 4)
        return [int(xs.min()), int(xs.max()), int(ys.min()), int(ys.max())] if xs.size else None

    return {"mean_rgb_a": a.reshape(-1, 3).mean(0).round(2).tolist(),
            "mean_rgb_b": b.reshape(-1, 3).mean(0).round(2).tolist(),
            "mean_abs": round(float(d.mean()), 3), "max_abs": int(d.max()),
            "rmse": round(float(np.sqrt((d ** 2).mean())), 3),
            "psnr_db": round(float(20 * np.log10(255 / max(np.sqrt((d ** 2).mean()), 1e-9))), 2),
            "px_over_8": round(float((d.max(axis=2) > 8).mean()) * 100, 3),
            "footprint_a": footprint(a), "footprint_b": footprint(b)}


def summary(xs):
    return f"min {min(xs):7.1f}  median {statistics.median(xs):7.1f}"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build-dir", default=os.path.join(REPO, "build"), help="where ./setup.sh builds (default)")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--frames", type=int, default=5, help="timed frames per process (VTK: after a warm-up)")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--image", dest="size", type=int, default=1024, help="image edge in pixels (N: NxN)")
    p.add_argument("--scene", help="a scene file with a cubic volume generator (default: the built-in scene)")
    p.add_argument("--no-shading", action="store_true", help="leave out the scene's shading")
    p.add_argument("--generator", default="hollow-shell", help="without --scene: hollow-shell | marschner-lobb | noise-cloud | head")
    p.add_argument("--volume-size", dest="volume_size_given", type=int, help="volume edge (default: the scene's, 256)")
    p.add_argument("--out-dir", default=os.path.join("bench-out", "vtk-compare"),
                   help="where the two PNGs go (default bench-out/vtk-compare; --out-dir docs refreshes the README's)")
    p.add_argument("--prefix", default="vtk-compare", help="PNG names: <prefix>-vtk.png, <prefix>-tessera.png")
    p.add_argument("--vtk-worker", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--raw", help=argparse.SUPPRESS)
    p.add_argument("--png", help=argparse.SUPPRESS)
    p.add_argument("--case", help=argparse.SUPPRESS)
    args = p.parse_args()
    args.volume_size = args.volume_size_given or 256
    require_modules()
    if args.vtk_worker:
        return vtk_worker(args)

    if not os.environ.get("DISPLAY"):
        if not shutil.which("xvfb-run"):
            sys.exit("vtk_compare: Debian's VTK needs an X display for offscreen rendering; apt-get install -y xvfb")
        os.execvp("xvfb-run", ["xvfb-run", "-a", "-s", "-screen 0 1280x1280x24", sys.executable,
                               os.path.abspath(__file__)] + sys.argv[1:])

    bindir = os.path.join(args.build_dir, "bin")
    render, dump = os.path.join(bindir, "tessera-render"), os.path.join(bindir, "tessera-dump-volume")
    if not (os.access(render, os.X_OK) and os.access(dump, os.X_OK)):
        sys.exit(f"vtk_compare: build them first: cmake --build {args.build_dir} "
                 "--target tessera-render tessera-dump-volume -j2")
    args.out_dir = os.path.abspath(args.out_dir)
    os.makedirs(args.out_dir, exist_ok=True)
    vtk_png = os.path.join(args.out_dir, f"{args.prefix}-vtk.png")
    tes_png = os.path.join(args.out_dir, f"{args.prefix}-tessera.png")

    case = load_case(args)
    with tempfile.TemporaryDirectory(prefix="vtk_compare_") as tmp:
        raw = os.path.join(tmp, "volume.raw")
        subprocess.run([dump, case["generator"], str(case["volume_size"]), "1", raw], check=True, capture_output=True)
        scene, case_json = os.path.join(tmp, "scene.yaml"), os.path.join(tmp, "case.json")
        with open(scene, "w") as f:
            f.write(scene_yaml(case, args.size))
        with open(case_json, "w") as f:
            json.dump(case, f)
        shading = "shading " + json.dumps(case["shading"]) if case["shading"] else "no shading"
        print(f"case: {args.scene or 'built-in scene'}: {case['generator']} {case['volume_size']}^3, {shading}, "
              f"light {case['light'] or 'headlight'}, blend {case['blend']}, {args.size}x{args.size}, one-voxel step, "
              f"{args.threads} threads; {args.rounds} rounds of (VTK, Tessera skip, Tessera no-skip), "
              f"best of {args.frames} frames each", flush=True)
        rows = []
        for r in range(args.rounds):
            last = r == args.rounds - 1
            v = run_vtk(args, raw, case_json, vtk_png if last else None)
            t_skip, c_skip, cmd_skip = tessera_frame(args, render, scene, tes_png, False)
            t_noskip, c_noskip, cmd_noskip = tessera_frame(args, render, scene, os.path.join(tmp, "noskip.png"), True)
            row = {"vtk": min(v["wall_ms"]), "vtk_median_frame": statistics.median(v["wall_ms"]),
                   "vtk_mapper": min(v["mapper_ms"]), "vtk_warm": v["warm_ms"],
                   "skip": t_skip, "noskip": t_noskip, "vtk_cpu": statistics.median(v["cpu_ms"]),
                   "skip_cpu": c_skip, "noskip_cpu": c_noskip, "load": os.getloadavg()[0]}
            rows.append(row)
            print(f"round {r + 1}: VTK {row['vtk']:.1f} ms (mapper {row['vtk_mapper']:.1f}, frames "
                  f"{', '.join(f'{x:.0f}' for x in v['wall_ms'])}, warm-up {v['warm_ms']:.0f}; "
                  f"VTK {v['vtk']}, {v['threads']} threads) | Tessera skip {t_skip:.1f} ms | "
                  f"no-skip {t_noskip:.1f} ms | CPU ms/frame: VTK {row['vtk_cpu']:.0f}, skip {c_skip:.0f}, "
                  f"no-skip {c_noskip:.0f} | load {row['load']:.1f}", flush=True)

    col = lambda k: [x[k] for x in rows]  # noqa: E731
    ratio_skip = [x["vtk"] / x["skip"] for x in rows]
    ratio_noskip = [x["vtk"] / x["noskip"] for x in rows]
    print("\nms/frame over rounds (each round: best of its frames)")
    print(f"  VTK fixed-point ray cast (wall per Render) {summary(col('vtk'))}")
    print(f"  VTK mapper time-to-draw                    {summary(col('vtk_mapper'))}")
    print(f"  Tessera, empty-space skipping              {summary(col('skip'))}")
    print(f"  Tessera, --no-skip                         {summary(col('noskip'))}")
    print(f"  VTK / Tessera skip    (per round)  min {min(ratio_skip):.2f}  median {statistics.median(ratio_skip):.2f}")
    print(f"  VTK / Tessera no-skip (per round)  min {min(ratio_noskip):.2f}  median "
          f"{statistics.median(ratio_noskip):.2f}")
    print("CPU ms per frame, all threads (less sensitive to other processes on a shared machine)")
    print(f"  VTK (median frame of each round)           {summary(col('vtk_cpu'))}")
    print(f"  Tessera, empty-space skipping              {summary(col('skip_cpu'))}")
    print(f"  Tessera, --no-skip                         {summary(col('noskip_cpu'))}")
    cr_skip = [x["vtk_cpu"] / x["skip_cpu"] for x in rows]
    cr_noskip = [x["vtk_cpu"] / x["noskip_cpu"] for x in rows]
    print(f"  VTK / Tessera skip    (per round)  min {min(cr_skip):.2f}  median {statistics.median(cr_skip):.2f}")
    print(f"  VTK / Tessera no-skip (per round)  min {min(cr_noskip):.2f}  median "
          f"{statistics.median(cr_noskip):.2f}")
    print(f"  1-minute load average during rounds        {summary(col('load'))}")
    print(f"  tessera command: {cmd_skip}\n  tessera command: {cmd_noskip}")
    print(f"\nimages: {vtk_png} vs {tes_png}")
    print("  " + json.dumps(compare_images(vtk_png, tes_png)))


if __name__ == "__main__":
    main()
