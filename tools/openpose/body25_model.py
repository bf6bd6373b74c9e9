"""OpenPose's BODY_25 body network as a torch module (for the ort backend's fixtures; no real weights here).

Written from the layer list of OpenPose's models/pose/body_25/pose_deploy.prototxt (as reproduced in the
pytorch-openpose style ports): the VGG-19 front end of the COCO model (conv1_1..conv4_2, conv4_3_CPM,
conv4_4_CPM) with PReLU instead of ReLU from conv4_2 on; then 4 PAF stages ("L2", 52 channels) and 2 heatmap
stages ("L1", 26 channels). Every stage has 5 "Mconv" blocks of three 3x3 convs whose outputs are concatenated
(each followed by a PReLU), then a 1x1 conv (PReLU) and a 1x1 output conv without activation:
  PAF stage 0: in 128 (features), 96 channels per conv (block out 288), Mconv6 256;
  PAF stages 1-3: in 128 + 52 (features, previous PAF), 128 per conv (384), Mconv6 512;
  heatmap stage 0: in 128 + 52 (features, last PAF), 96 per conv (288), Mconv6 256;
  heatmap stage 1: in 128 + 26 + 52 (features, heatmap stage 0, last PAF), 128 per conv (384), Mconv6 512.
The caffe net's single output is concat(heatmaps 26, PAFs 52) = 78 channels; `forward` returns the same.
"""
import torch
import torch.nn as nn

PAF, HEAT = 52, 26


def conv(cin, cout, k):
    return nn.Conv2d(cin, cout, k, 1, k // 2)


class Front(nn.Module):
    def __init__(self):
        super().__init__()
        spec = [("conv1_1", 3, 64), ("conv1_2", 64, 64), "pool", ("conv2_1", 64, 128), ("conv2_2", 128, 128),
                "pool", ("conv3_1", 128, 256), ("conv3_2", 256, 256), ("conv3_3", 256, 256),
                ("conv3_4", 256, 256), "pool", ("conv4_1", 256, 512), ("conv4_2", 512, 512),
                ("conv4_3_CPM", 512, 256), ("conv4_4_CPM", 256, 128)]
        prelu = {"conv4_2", "conv4_3_CPM", "conv4_4_CPM"}
        layers = []
        for s in spec:
            if s == "pool":
                layers.append(nn.MaxPool2d(2, 2))
                continue
            name, cin, cout = s
            layers.append(conv(cin, cout, 3))
            layers.append(nn.PReLU(cout) if name in prelu else nn.ReLU())
        self.layers = nn.Sequential(*layers)

    def forward(self, x):
        return self.layers(x)


class DenseBlock(nn.Module):
    """Three 3x3 conv + PReLU in a row; the output is the concatenation of all three."""

    def __init__(self, cin, width):
        super().__init__()
        self.convs = nn.ModuleList([conv(cin, width, 3), conv(width, width, 3), conv(width, width, 3)])
        self.prelus = nn.ModuleList([nn.PReLU(width) for _ in range(3)])

    def forward(self, x):
        outs = []
        for c, p in zip(self.convs, self.prelus):
            x = p(c(x))
            outs.append(x)
        return torch.cat(outs, 1)


class Stage(nn.Module):
    def __init__(self, cin, width, mid, cout):
        super().__init__()
        self.blocks = nn.ModuleList([DenseBlock(cin if i == 0 else 3 * width, width) for i in range(5)])
        self.mconv6 = conv(3 * width, mid, 1)
        self.prelu6 = nn.PReLU(mid)
        self.mconv7 = conv(mid, cout, 1)

    def forward(self, x):
        for b in self.blocks:
            x = b(x)
        return self.mconv7(self.prelu6(self.mconv6(x)))


class Body25(nn.Module):
    def __init__(self):
        super().__init__()
        self.front = Front()
        self.paf = nn.ModuleList([Stage(128, 96, 256, PAF)] + [Stage(128 + PAF, 128, 512, PAF) for _ in range(3)])
        self.heat0 = Stage(128 + PAF, 96, 256, HEAT)
        self.heat1 = Stage(128 + HEAT + PAF, 128, 512, HEAT)

    def forward(self, x):
        f = self.front(x)
        paf = self.paf[0](f)
        for s in self.paf[1:]:
            paf = s(torch.cat([f, paf], 1))
        h0 = self.heat0(torch.cat([f, paf], 1))
        h1 = self.heat1(torch.cat([f, h0, paf], 1))
        return torch.cat([h1, paf], 1)
