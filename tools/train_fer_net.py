#!/usr/bin/python3
"""Fine-tunes face-api.js's expression network for the pipeline's expression model (issue 20).

Input: the network's input pixels of the pipeline's two views of every face, as
build/bench/fer_crops writes them (the eye-aligned crop and the package's landmark box crop,
both made by our own C++ exactly as the analyser makes them).

Model (the shipped method `face_api:no_flip:unbalanced:l2=1:blocks=face_api+face_api_box:tta=flip`,
with the network trainable): per view the network's 256 pooled features and its 7 logits, the
two views concatenated (526), standardised with fixed statistics, one linear softmax layer;
class probabilities averaged with the mirror image at test time. The first `--frozen` dense
blocks keep the package's weights (their outputs are computed once), the others, the package's
own classifier layer and the softmax layer are trained (cross-entropy with label smoothing,
AdamW, one-cycle learning rate, dropout before the softmax layer), starting from the package's
weights and from the softmax layer that the frozen network's features give (the baseline,
measured in the same run). Augmentation: mirror images, and with `--frozen 0` (the shipped
model) small rotations, zooms, shifts and contrast/brightness changes of the input pixels;
with frozen blocks, shifts of their output maps.

  train_fer_net.py CROPS.bin --cv 5 [--seed 12]       cross-validation: baseline vs fine-tuned
      [--save-probs P.npz] [--fold-seed S]            every tested face's class probabilities
                                                      (baseline and fine-tuned, face and
                                                      mirror) for comparing combinations;
                                                      folds of another seed than --seed
  train_fer_net.py CROPS.bin --out-dir D --model Y    train on every face, write the network
                                                      (TF.js manifest + float32 binary in D) and
                                                      the expression model Y that uses it

CROPS.bin: build/bench/fer_crops fer2013 DIR CROPS.bin (Release build with benchmarks).
The shipped model: modalities/expression/models/MODEL_CARD.md ("Re-create").
Needs python3-torch and python3-numpy (Debian; DREAMSENSE_SETUP_TRAINING=1 bash tools/setup.sh).
Deterministic for a given seed and thread count.
"""
import argparse
import json
import os
import struct
import sys
import time

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

MEAN = (122.782, 117.001, 104.298)  # the package's RGB mean (face_api_net.cpp)
LABELS = ["anger", "disgust", "fear", "happy", "sadness", "surprise", "neutral"]
CHANNELS = [3, 32, 64, 128, 256]


def read_crops(path):
    with open(path, "rb") as f:
        magic, version, n, side = struct.unpack("<4i", f.read(16))
        if magic != 0x43465344 or version != 1:
            sys.exit(f"{path}: not a fer_crops file")
        rec = 8 + 2 * side * side
        raw = np.frombuffer(f.read(n * rec), dtype=np.uint8)
    if raw.size != n * rec:
        sys.exit(f"{path}: truncated")
    raw = raw.reshape(n, rec)
    head = raw[:, :8].copy().view("<i4")
    # fer_crops writes expression::kExpressionLabels indices (contempt at 1: FER2013 has none)
    eight = ["anger", "contempt", "disgust", "fear", "happy", "sadness", "surprise", "neutral"]
    to_seven = np.array([LABELS.index(n) if n in LABELS else -1 for n in eight])
    labels, sources = to_seven[head[:, 0]], head[:, 1]
    if (labels < 0).any():
        sys.exit(f"{path}: a face of a class the model does not have (contempt)")
    views = raw[:, 8:].reshape(n, 2, side, side)
    return labels, sources, views


def load_manifest(model_dir, name="face_expression_model"):
    with open(os.path.join(model_dir, f"{name}-weights_manifest.json")) as f:
        return read_weights(json.load(f), model_dir)


def read_weights(manifest, model_dir):
    """A TF.js weights manifest's tensors (float32, int32 or quantised) by name."""
    out = {}
    for group in manifest:
        data = b"".join(open(os.path.join(model_dir, p), "rb").read() for p in group["paths"])
        off = 0
        for w in group["weights"]:
            n = int(np.prod(w["shape"]))
            q = w.get("quantization")
            if q:
                dt = {"uint8": np.uint8, "uint16": np.uint16}[q["dtype"]]
                v = np.frombuffer(data, dtype=dt, count=n, offset=off).astype(np.float64)
                v = (v * q["scale"] + q["min"]).astype(np.float32)
                off += n * np.dtype(dt).itemsize
            else:  # float32, or int32 (a graph model's constants)
                dt = "<i4" if w.get("dtype") == "int32" else "<f4"
                v = np.frombuffer(data, dtype=dt, count=n, offset=off).copy()
                off += n * 4
            out[w["name"]] = v.reshape(w["shape"])
    return out


def same_pad(x, stride):
    # TF "SAME" for 3x3: stride 1 pads 1 on every side; stride 2 on an even size pads only the
    # bottom and right.
    return F.pad(x, (1, 1, 1, 1)) if stride == 1 else F.pad(x, (0, 1, 0, 1))


class Separable(nn.Module):
    def __init__(self, cin, cout, stride):
        super().__init__()
        self.stride = stride
        self.dw = nn.Conv2d(cin, cin, 3, stride, groups=cin, bias=False)
        self.pw = nn.Conv2d(cin, cout, 1)

    def forward(self, x):
        return self.pw(self.dw(same_pad(x, self.stride)))


class FullConv(nn.Module):
    def __init__(self, cin, cout, stride):
        super().__init__()
        self.stride = stride
        self.conv = nn.Conv2d(cin, cout, 3, stride)

    def forward(self, x):
        return self.conv(same_pad(x, self.stride))


class DenseBlock(nn.Module):
    def __init__(self, cin, cout, first):
        super().__init__()
        self.conv0 = FullConv(cin, cout, 2) if first else Separable(cin, cout, 2)
        self.conv1 = Separable(cout, cout, 1)
        self.conv2 = Separable(cout, cout, 1)
        self.conv3 = Separable(cout, cout, 1)

    def forward(self, x):
        out1 = F.relu(self.conv0(x))
        out2 = self.conv1(out1)
        out3 = self.conv2(F.relu(out1 + out2))
        out4 = self.conv3(F.relu(out1 + out2 + out3))
        return F.relu(out1 + out2 + out3 + out4)


class ExpressionNet(nn.Module):
    def __init__(self):
        super().__init__()
        self.blocks = nn.ModuleList(
            DenseBlock(CHANNELS[b], CHANNELS[b + 1], b == 0) for b in range(4))
        self.fc = nn.Linear(256, 7)

    def trunk(self, x, first, last):
        for b in range(first, last):
            x = self.blocks[b](x)
        return x

    def features(self, x, first=0):
        """263 features (pooled 256, logits 7) from the input of block `first`."""
        pooled = self.trunk(x, first, 4).mean(dim=(2, 3))
        return torch.cat([pooled, self.fc(pooled)], dim=1)

    def load_tf(self, w):
        t = lambda a: torch.from_numpy(np.ascontiguousarray(a))
        for b, block in enumerate(self.blocks):
            p = f"dense{b}"
            if b == 0:
                block.conv0.conv.weight.data = t(w[f"{p}/conv0/filters"].transpose(3, 2, 0, 1))
                block.conv0.conv.bias.data = t(w[f"{p}/conv0/bias"])
            for k in range(0 if b else 1, 4):
                conv = getattr(block, f"conv{k}")
                conv.dw.weight.data = t(w[f"{p}/conv{k}/depthwise_filter"].transpose(2, 3, 0, 1))
                conv.pw.weight.data = t(w[f"{p}/conv{k}/pointwise_filter"].transpose(3, 2, 0, 1))
                conv.pw.bias.data = t(w[f"{p}/conv{k}/bias"])
        self.fc.weight.data = t(w["fc/weights"].T)
        self.fc.bias.data = t(w["fc/bias"])

    def tf_weights(self):
        """(name, array in the package's TF layout) in the package's manifest order."""
        n = lambda p: p.detach().numpy().astype(np.float32)
        out = []
        for b, block in enumerate(self.blocks):
            p = f"dense{b}"
            if b == 0:
                out.append((f"{p}/conv0/filters", n(block.conv0.conv.weight).transpose(2, 3, 1, 0)))
                out.append((f"{p}/conv0/bias", n(block.conv0.conv.bias)))
            for k in range(0 if b else 1, 4):
                conv = getattr(block, f"conv{k}")
                out.append((f"{p}/conv{k}/depthwise_filter",
                            n(conv.dw.weight).transpose(2, 3, 0, 1)))
                out.append((f"{p}/conv{k}/pointwise_filter",
                            n(conv.pw.weight).transpose(2, 3, 1, 0)))
                out.append((f"{p}/conv{k}/bias", n(conv.pw.bias)))
        out.append(("fc/weights", n(self.fc.weight).T))
        out.append(("fc/bias", n(self.fc.bias)))
        return out


def to_input(grey_u8):
    """uint8 N x side x side grey -> the network's normalised N x 3 x side x side input."""
    g = torch.from_numpy(np.ascontiguousarray(grey_u8)).float().unsqueeze(1)
    return torch.cat([(g - m) / 255.0 for m in MEAN], dim=1)


@torch.no_grad()
def frozen_maps(net, views, frozen, batch=64):
    """The output of the first `frozen` blocks for every face, view and mirror:
    N x 2 (mirror) x 2 (view) x C x H x W, float16 to save memory."""
    out = None
    n = views.shape[0]
    for i in range(0, n, batch):
        chunk = views[i:i + batch]
        maps = []
        for mirror in (False, True):
            for v in range(2):
                if frozen == 0:  # the grey pixels (0..255), normalised in Model
                    x = torch.from_numpy(np.ascontiguousarray(chunk[:, v])).float().unsqueeze(1)
                    maps.append(torch.flip(x, dims=[3]) if mirror else x)
                    continue
                x = to_input(chunk[:, v, :, :])
                if mirror:
                    x = torch.flip(x, dims=[3])
                maps.append(net.trunk(x, 0, frozen))
        m = torch.stack(maps, dim=1).view(chunk.shape[0], 2, 2, *maps[0].shape[1:])
        if out is None:
            out = torch.empty((n, *m.shape[1:]), dtype=torch.float16)
        out[i:i + chunk.shape[0]] = m.half()
    return out


class Model(nn.Module):
    """Two views through the (partly trainable) network, standardised, softmax layer."""

    def __init__(self, net, frozen, mean, inv_std):
        super().__init__()
        self.net, self.frozen = net, frozen
        self.register_buffer("mean", mean)
        self.register_buffer("inv_std", inv_std)
        self.head = nn.Linear(526, 7)
        self.drop = nn.Dropout(0.0)

    def view_features(self, m):
        if self.frozen == 0:  # grey pixels -> the network's normalised RGB input
            m = torch.cat([(m - c) / 255.0 for c in MEAN], dim=1)
        return self.net.features(m, self.frozen)

    def standardised(self, maps):  # maps: B x 2 (view) x C x H x W
        f = torch.cat([self.view_features(maps[:, v].float()) for v in range(2)], 1)
        return (f - self.mean) * self.inv_std

    def forward(self, maps):
        return self.head(self.drop(self.standardised(maps)))


def fit_softmax(x, y, l2, iters=300):
    """Mean cross-entropy + l2/2 |W|^2 (bias free), as vision::train_softmax (unbalanced)."""
    head = nn.Linear(x.shape[1], 7).double()
    nn.init.zeros_(head.weight)
    nn.init.zeros_(head.bias)
    xd = x.double()
    opt = torch.optim.LBFGS(head.parameters(), lr=1, max_iter=iters, tolerance_change=1e-10,
                            history_size=20, line_search_fn="strong_wolfe")

    def closure():
        opt.zero_grad()
        loss = F.cross_entropy(head(xd), y) + 0.5 * l2 * (head.weight ** 2).sum()
        loss.backward()
        return loss

    opt.step(closure)
    return head.float()


@torch.no_grad()
def in_batches(model, maps, fn, batch=32):
    """fn(model, batch of maps) over every face, in evaluation mode, concatenated. Small batches:
    at 256 the passes spent most of their time allocating (88 s against 3.2 s for 512 faces)."""
    model.eval()
    return torch.cat([fn(model, maps[i:i + batch]) for i in range(0, maps.shape[0], batch)])


def predict_each(model, maps):
    """Class probabilities of the face and of its mirror image: N x 2 (mirror) x 7."""
    return in_batches(model, maps, lambda mo, m: torch.stack(
        [F.softmax(mo(m[:, k]), dim=1) for k in range(2)], 1))


def predict(model, maps):
    """Class probabilities averaged over the face and its mirror image."""
    return predict_each(model, maps).mean(1)


def unmirrored_features(model, maps):
    """Standardisation-free features of the faces as they are (N x 526), as the C++ fit uses."""
    return in_batches(model, maps, lambda mo, m: torch.cat(
        [mo.view_features(m[:, 0, v].float()) for v in range(2)], 1))


def shift_maps(m, max_shift):
    """Feature-map translation by up to max_shift cells (edge cells repeated)."""
    if max_shift == 0:
        return m
    dy, dx = np.random.randint(-max_shift, max_shift + 1, size=2)
    h, w = m.shape[-2:]
    p = F.pad(m.flatten(0, 1), (max_shift,) * 4, mode="replicate")
    p = p.view(*m.shape[:3], h + 2 * max_shift, w + 2 * max_shift)
    return p[..., max_shift + dy:max_shift + dy + h, max_shift + dx:max_shift + dx + w]


def augment_pixels(m, rotate_deg, scale, shift, light):
    """Random similarity (rotation, scale, shift in crop fractions; edge pixels repeated) and
    contrast/brightness per face, the same for both views: B x 2 x 1 x H x W grey pixels."""
    b = m.shape[0]
    a = (torch.rand(b) * 2 - 1) * rotate_deg * np.pi / 180
    k = 1 + (torch.rand(b) * 2 - 1) * scale
    t = (torch.rand(b, 2) * 2 - 1) * shift * 2  # affine_grid's units: half the side
    theta = torch.zeros(b, 2, 3)
    theta[:, 0, 0], theta[:, 0, 1] = torch.cos(a) / k, -torch.sin(a) / k
    theta[:, 1, 0], theta[:, 1, 1] = torch.sin(a) / k, torch.cos(a) / k
    theta[:, :, 2] = t
    flat = m.transpose(0, 1).flatten(0, 1)  # views outer: 2B x 1 x H x W
    grid = F.affine_grid(theta.repeat(2, 1, 1), flat.shape, align_corners=False)
    out = F.grid_sample(flat, grid, mode="bilinear", padding_mode="border", align_corners=False)
    gain = 1 + (torch.rand(b) * 2 - 1) * light
    bias = (torch.rand(b) * 2 - 1) * light * 64
    out = out.view(2, b, *m.shape[2:]).transpose(0, 1)
    out = (out - 128) * gain.view(b, 1, 1, 1, 1) + 128 + bias.view(b, 1, 1, 1, 1)
    return out.clamp(0, 255)


def train(base_state, maps, y, args, log=None):
    """Baseline softmax layer on the package's features, then fine-tuning. Returns both models."""
    net = ExpressionNet()
    net.load_state_dict(base_state)
    model = Model(net, args.frozen, torch.zeros(526), torch.ones(526))
    feats = unmirrored_features(model, maps)
    mean = feats.mean(0)
    std = feats.std(0, unbiased=False)
    inv_std = torch.where(std > 1e-6, 1.0 / std, torch.zeros_like(std))
    model.mean.copy_(mean)
    model.inv_std.copy_(inv_std)
    head = fit_softmax((feats - mean) * inv_std, y, args.baseline_l2)
    model.head.load_state_dict(head.state_dict())
    baseline = Model(ExpressionNet(), args.frozen, mean.clone(), inv_std.clone())
    baseline.load_state_dict(model.state_dict())
    if args.epochs == 0:
        return baseline, model
    model.drop.p = args.dropout
    backbone = [p for b in net.blocks[args.frozen:] for p in b.parameters()] + list(
        net.fc.parameters())
    for b in net.blocks[:args.frozen]:
        for p in b.parameters():
            p.requires_grad_(False)
    opt = torch.optim.AdamW([{"params": backbone, "lr": args.lr},
                             {"params": model.head.parameters(), "lr": args.head_lr}],
                            weight_decay=args.weight_decay)
    n = maps.shape[0]
    steps = args.epochs * ((n + args.batch - 1) // args.batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(
        opt, max_lr=[args.lr, args.head_lr], total_steps=steps, pct_start=0.15)
    for epoch in range(args.epochs):
        model.train()
        # frozen blocks have no batch norm; train() only switches dropout on
        order = torch.randperm(n)
        total, t0 = 0.0, time.time()
        for i in range(0, n, args.batch):
            idx = order[i:i + args.batch]
            mirror = torch.randint(0, 2, (idx.shape[0],))
            m = maps[idx, mirror].float()
            if args.frozen == 0:
                m = augment_pixels(m, args.rotate, args.scale, args.shift_px, args.light)
            else:
                m = shift_maps(m, args.shift)
            loss = F.cross_entropy(model(m), y[idx], label_smoothing=args.smoothing)
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            total += loss.item() * idx.shape[0]
        if log:
            log(f"  epoch {epoch + 1}/{args.epochs} loss {total / n:.4f} ({time.time() - t0:.0f} s)")
    return baseline, model


def accuracy(p, y):
    return float((p.argmax(1) == y).float().mean())


def balanced(p, y):
    pred = p.argmax(1)
    return float(np.mean([float((pred[y == k] == k).float().mean()) for k in range(7)
                          if (y == k).any()]))


def fnv1a_hex(data):
    h = 1469598103934665603
    for c in data:
        h ^= c
        h = (h * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


def yaml_matrix(name, values, indent):
    pad = " " * indent
    v = np.asarray(values, dtype=np.float32)
    rows, cols = (1, v.size) if v.ndim == 1 else v.shape
    data = ", ".join(repr(float(x)) for x in v.ravel())
    return (f"{pad}{name}: !!opencv-matrix\n{pad}   rows: {rows}\n{pad}   cols: {cols}\n"
            f"{pad}   dt: f\n{pad}   data: [ {data} ]\n")


def write_network(net, out_dir):
    os.makedirs(out_dir, exist_ok=True)
    weights = net.tf_weights()
    blob = b"".join(a.astype("<f4").tobytes() for _, a in weights)
    with open(os.path.join(out_dir, "face_expression_model.bin"), "wb") as f:
        f.write(blob)
    manifest = [{"paths": ["face_expression_model.bin"],
                 "weights": [{"name": n, "shape": list(a.shape), "dtype": "float32"}
                             for n, a in weights]}]
    with open(os.path.join(out_dir, "face_expression_model-weights_manifest.json"), "w") as f:
        json.dump(manifest, f, indent=1)
        f.write("\n")
    return fnv1a_hex(blob)


def write_model(path, model, network_dir, weights_hash, items, note):
    rel = os.path.relpath(network_dir, os.path.dirname(os.path.abspath(path)))
    name = "face_api:no_flip:unbalanced:l2=1:blocks=face_api+face_api_box:tta=flip"
    text = ["%YAML:1.0", "---", "format: dreamsense-expression-model", "version: 1", "method:",
            f'   name: "{name}"', "   blocks:", "      - face_api", "      - face_api_box",
            "   alignment_size: 64", "   eye_distance: 0.4", "   eye_row: 0.34", "   lbp_grid: 8",
            "   lbp_sqrt: 0", "   hog_cell_px: 8", "   hog_bins: 9", "   face_api_flip: 0",
            "   classifier: softmax", "   standardize: 1", "   train_mirrored: 0",
            "   test_mirrored: 0", '   train_augment: ""', "   test_augment: flip",
            "   svm_c: 0.1", "   softmax_l2: 1.", "   balance_classes: 0",
            f'   face_api_network: "{rel}"', "labels:"]
    text += [f"   - {label}" for label in LABELS]
    text += ["training:", "   dataset: fer2013", f"   items: {items}", f'   note: "{note}"',
             f'face_api_weights_hash: "{weights_hash}"', "standardizer:"]
    body = "\n".join(text) + "\n"
    body += yaml_matrix("mean", model.mean, 3)
    body += yaml_matrix("inv_std", model.inv_std, 3)
    body += "classifier:\n"
    body += yaml_matrix("weights", model.head.weight.detach(), 3)
    body += yaml_matrix("bias", model.head.bias.detach(), 3)
    with open(path, "w") as f:
        f.write(body)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("crops")
    ap.add_argument("--face-api-dir", default="/usr/lib/node_modules/@vladmandic/face-api/model")
    ap.add_argument("--cv", type=int, default=0, help="folds of a cross-validation")
    ap.add_argument("--first-folds", type=int, default=0,
                    help="run only the first N folds of the cross-validation (quick comparisons)")
    ap.add_argument("--seed", type=int, default=12)
    ap.add_argument("--fold-seed", type=int,
                    help="seed of the cross-validation folds (default: --seed), so that models "
                         "trained with other seeds can be compared and averaged on the same folds")
    ap.add_argument("--frozen", type=int, default=0, help="dense blocks kept as the package's")
    ap.add_argument("--epochs", type=int, default=12)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--lr", type=float, default=3e-4)
    ap.add_argument("--head-lr", type=float, default=1e-3)
    ap.add_argument("--weight-decay", type=float, default=1e-2)
    ap.add_argument("--dropout", type=float, default=0.3)
    ap.add_argument("--shift", type=int, default=1, help="feature-map shift augmentation (cells)")
    ap.add_argument("--rotate", type=float, default=10, help="pixel augmentation (--frozen 0)")
    ap.add_argument("--scale", type=float, default=0.1)
    ap.add_argument("--shift-px", type=float, default=0.05, help="of the crop side")
    ap.add_argument("--light", type=float, default=0.2, help="contrast and brightness")
    ap.add_argument("--smoothing", type=float, default=0.1, help="label smoothing")
    ap.add_argument("--baseline-l2", type=float, default=1.0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out-dir")
    ap.add_argument("--model")
    ap.add_argument("--json")
    ap.add_argument("--save-probs", help="with --cv: .npz of every tested face's probabilities")
    args = ap.parse_args()
    if not args.cv and not (args.out_dir and args.model):
        ap.error("give --cv K, or --out-dir and --model")
    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    np.random.seed(args.seed)
    log = lambda s: print(s, file=sys.stderr, flush=True)

    labels, sources, views = read_crops(args.crops)
    y = torch.from_numpy(labels)
    base = ExpressionNet()
    base.load_tf(load_manifest(args.face_api_dir))
    base_state = base.state_dict()
    t0 = time.time()
    maps = frozen_maps(base, views, args.frozen)
    log(f"{len(labels)} faces; frozen blocks' outputs {tuple(maps.shape)} in "
        f"{time.time() - t0:.0f} s")

    if args.cv:
        rng = np.random.RandomState(args.seed if args.fold_seed is None else args.fold_seed)
        fold = np.empty(len(labels), dtype=np.int64)
        fold[rng.permutation(len(labels))] = np.arange(len(labels)) % args.cv
        p_base = torch.zeros(len(labels), 2, 7)
        p_tuned = torch.zeros(len(labels), 2, 7)
        run = range(args.cv if not args.first_folds else min(args.cv, args.first_folds))
        for k in run:
            tr, te = np.where(fold != k)[0], np.where(fold == k)[0]
            t0 = time.time()
            b, m = train(base_state, maps[tr], y[tr], args, log)
            p_base[te] = predict_each(b, maps[te])
            p_tuned[te] = predict_each(m, maps[te])
            log(f"fold {k + 1}/{args.cv}: baseline {accuracy(p_base[te].mean(1), y[te]):.3f} "
                f"fine-tuned {accuracy(p_tuned[te].mean(1), y[te]):.3f} "
                f"({time.time() - t0:.0f} s)")
        result = {"folds": args.cv, "seed": args.seed, "faces": len(labels),
                  "settings": {k: v for k, v in vars(args).items()
                               if k not in ("crops", "json", "out_dir", "model", "save_probs")}}
        tested = torch.from_numpy(np.isin(fold, list(run)))
        result["faces_tested"] = int(tested.sum())
        if args.save_probs:  # per face and mirror, for comparing test-time combinations
            np.savez_compressed(args.save_probs, fold=fold, label=labels, source=sources,
                                baseline=p_base.numpy(), fine_tuned=p_tuned.numpy())
        p_base, p_tuned = p_base.mean(1), p_tuned.mean(1)
        for name, p in (("baseline", p_base), ("fine_tuned", p_tuned)):
            p, yt = p[tested], y[tested]
            pred = p.argmax(1)
            result[name] = {
                "accuracy": accuracy(p, yt), "balanced_accuracy": balanced(p, yt),
                "per_class_recall": {LABELS[c]: float((pred[yt == c] == c).float().mean())
                                     for c in range(7)}}
        print(json.dumps(result, indent=1))
        if args.json:
            with open(args.json, "w") as f:
                json.dump(result, f, indent=1)
        return

    _, model = train(base_state, maps, y, args, log)
    # The exported network holds the frozen blocks' original weights and the trained ones.
    weights_hash = write_network(model.net, args.out_dir)
    note = ("tools/train_fer_net.py " + os.path.basename(args.crops) + " " +
            " ".join(f"--{k.replace('_', '-')} {v}" for k, v in vars(args).items()
                     if k in ("seed", "frozen", "epochs", "batch", "lr", "head_lr",
                              "weight_decay", "dropout", "shift", "rotate", "scale", "shift_px",
                              "light", "smoothing", "threads")))
    write_model(args.model, model, args.out_dir, weights_hash, len(labels), note)
    log(f"wrote {args.out_dir} (weights {weights_hash}) and {args.model}")


if __name__ == "__main__":
    main()
