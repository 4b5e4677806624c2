#!/usr/bin/python3
"""The self-supervised integrator's training epoch written in PyTorch, timed on the CPU.

Issue 14 compares latentbench's trainer with "the same self-supervised loop written in
PyTorch on the CPU". This script is that loop for a shell scene (the cloth), so the
comparison can be measured on the machine at hand instead of quoted:

  * the same networks: the integrator MLP (Table 2 widths, swish, input standardised,
    z = z_prev + s ⊙ out) and the frozen decoder (latent → 3 residual blocks of 200 with
    BatchNorm in eval mode → 50 → 3N, PCA-initialised last layer, BC-relative decoding:
    positions = features + the Dirichlet targets' mean), as in the C++ trainer;
  * the same batch: every training sample every epoch, ceil(S / 256) near-equal batches,
    each doubled by a noisy copy (uniform noise of 0.1 × the batch's per-component std on
    z_prev and z_prev2); the clean copies' decoded inputs cached once, the noisy ones
    decoded every batch, as latentbench does;
  * the same loss: data balancing 1 / max(|mean vertex velocity|, 0.05 × its mean over the
    samples), the incremental potential ½/h² Σ m |x − x̃|² + membrane (StVK, plane stress)
    + hinge bending (w (θ − θ̄)²) − Σ m g·x + w_bc Σ_B |x − x*|² (w_bc = 1e5), averaged
    over the batch; Adam (lr 1e-3) on the integrator's weights; autograd for everything.

The element energies are checked, not assumed: --check evaluates the potential's gradient
at the dataset's own Newton solutions, where its free components must vanish (the
residual is printed relative to the weight of the cloth).

Like latentbench's `train_epoch/<scene>` benchmark, the networks are untrained (the
autoencoder is only PCA-initialised; latents are the first PCA coefficients): an epoch's
cost depends on the sizes, not on the values.

Needs Debian's python3-torch (not one of latentbench's dependencies):
  apt-get install python3-torch
  build/latentbench simulate experiments/scenes/cloth.toml -o cloth.h5
  /usr/bin/python3 scripts/torch_epoch.py cloth.h5 --threads 2 --epochs 50 --check
"""
import argparse
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plotting_common as pc  # noqa: E402  (the project's dataset reader and error exit)

try:
    import torch
except ImportError:
    pc.fail("PyTorch is not installed (Debian: apt-get install python3-torch)")

# Table 1/2 sizes of the full cloth (paper/paper_numbers.cpp).
LATENT = 4
INTEGRATOR_HIDDEN = [32, 32]
DECODER_HIDDEN = [200, 200, 200]
PCA_DIM = 50
PENALTY = 1e5
NOISE_FRACTION = 0.1
BALANCING_FLOOR = 0.05


class Shell:
    """Rest-state quantities of a triangle mesh (membrane and hinges), as the C++ energies."""

    def __init__(self, rest, triangles, youngs, poisson, thickness):
        mu = youngs / (2.0 * (1.0 + poisson)) * thickness
        lam = youngs * poisson / (1.0 - poisson * poisson) * thickness
        self.mu, self.lam = mu, lam
        x0, x1, x2 = (rest[triangles[:, k]] for k in range(3))
        e1, e2 = x1 - x0, x2 - x0
        normal = np.cross(e1, e2)
        area = 0.5 * np.linalg.norm(normal, axis=1)
        t1 = e1 / np.linalg.norm(e1, axis=1, keepdims=True)
        t2 = np.cross(normal / (2.0 * area[:, None]), t1)
        dm = np.stack([np.stack([(e1 * t1).sum(1), (e2 * t1).sum(1)], 1),
                       np.stack([(e1 * t2).sum(1), (e2 * t2).sum(1)], 1)], 1)
        self.triangles = triangles
        self.dm_inv = np.linalg.inv(dm)
        self.area = area
        # Hinges: every interior edge, its two ends and the two opposite vertices.
        opposite = {}
        for f, tri in enumerate(triangles):
            for k in range(3):
                a, b, c = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
                opposite.setdefault((min(a, b), max(a, b)), []).append((a, b, c))
        hinges = []
        for (a, b), sides in opposite.items():
            if len(sides) == 2:
                (p, q, c), (_, _, d) = sides
                hinges.append((p, q, c, d))
        self.hinges = np.array(hinges, dtype=np.int64)
        h = self.hinges
        e = rest[h[:, 1]] - rest[h[:, 0]]
        a1 = 0.5 * np.linalg.norm(np.cross(e, rest[h[:, 2]] - rest[h[:, 0]]), axis=1)
        a2 = 0.5 * np.linalg.norm(np.cross(rest[h[:, 3]] - rest[h[:, 0]], e), axis=1)
        stiffness = youngs * thickness ** 3 / (24.0 * (1.0 - poisson * poisson))
        self.hinge_weight = 3.0 * stiffness * (e * e).sum(1) / (a1 + a2)
        self.rest_angle = dihedral(torch.from_numpy(rest[None]), torch.from_numpy(self.hinges)).numpy()[0]

    def to(self, dtype):
        t = lambda a: torch.as_tensor(a, dtype=dtype)
        self.t_dm_inv, self.t_area = t(self.dm_inv), t(self.area)
        self.t_weight, self.t_rest = t(self.hinge_weight), t(self.rest_angle)
        self.t_tri = torch.as_tensor(self.triangles, dtype=torch.int64)
        self.t_hinges = torch.as_tensor(self.hinges, dtype=torch.int64)
        return self

    def elastic(self, x):
        """Membrane + bending energy of every sample; x: (B, N, 3)."""
        tri = self.t_tri
        x0 = x[:, tri[:, 0]]
        ds = torch.stack([x[:, tri[:, 1]] - x0, x[:, tri[:, 2]] - x0], dim=-1)  # (B, T, 3, 2)
        F = ds @ self.t_dm_inv  # (B, T, 3, 2)
        G = 0.5 * (F.transpose(-1, -2) @ F - torch.eye(2, dtype=x.dtype))
        tr = G[..., 0, 0] + G[..., 1, 1]
        psi = self.mu * (G * G).sum((-1, -2)) + 0.5 * self.lam * tr * tr
        membrane = (self.t_area * psi).sum(1)
        delta = wrap(dihedral(x, self.t_hinges) - self.t_rest)
        bending = (self.t_weight * delta * delta).sum(1)
        return membrane + bending


def dihedral(x, hinges):
    """θ = atan2(−|e| det(e, u, v), (e·u)(e·v) − |e|² (u·v)) of every hinge; x (B, N, 3)."""
    x0 = x[:, hinges[:, 0]]
    e, u, v = x[:, hinges[:, 1]] - x0, x[:, hinges[:, 2]] - x0, x[:, hinges[:, 3]] - x0
    det = (torch.linalg.cross(e, u, dim=-1) * v).sum(-1)
    ee = (e * e).sum(-1)
    X = (e * u).sum(-1) * (e * v).sum(-1) - ee * (u * v).sum(-1)
    return torch.atan2(-torch.sqrt(ee) * det, X)


def wrap(a):
    a = torch.where(a > math.pi, a - 2.0 * math.pi, a)
    return torch.where(a <= -math.pi, a + 2.0 * math.pi, a)


class Potential:
    """The incremental potential of one implicit-Euler step, per sample."""

    def __init__(self, shell, masses, gravity, dt, bc, dtype):
        self.shell = shell.to(dtype)
        self.m = torch.as_tensor(masses, dtype=dtype)
        self.g = torch.as_tensor(gravity, dtype=dtype)
        self.inv_dt2 = 1.0 / (dt * dt)
        self.bc = torch.as_tensor(bc, dtype=torch.int64)

    def __call__(self, x, x_tilde, targets, penalty=PENALTY):
        """x, x_tilde: (B, N, 3); targets (B, nB, 3) or None (no penalty)."""
        inertia = 0.5 * self.inv_dt2 * (self.m * ((x - x_tilde) ** 2).sum(-1)).sum(1)
        gravity = -(self.m * (x @ self.g)).sum(1)
        e = inertia + self.shell.elastic(x) + gravity
        if targets is not None:
            e = e + penalty * ((x[:, self.bc] - targets) ** 2).sum((1, 2))
        return e


class ResidualBlock(torch.nn.Module):
    def __init__(self, n_in, n_out):
        super().__init__()
        self.f = torch.nn.Sequential(torch.nn.Linear(n_in, n_out), torch.nn.BatchNorm1d(n_out), torch.nn.SiLU(),
                                     torch.nn.Linear(n_out, n_out), torch.nn.BatchNorm1d(n_out))
        self.skip = torch.nn.Linear(n_in, n_out) if n_in != n_out else None

    def forward(self, x):
        return self.f(x) + (self.skip(x) if self.skip is not None else x)


def make_decoder(features, basis, mean):
    layers, prev = [], LATENT
    for h in DECODER_HIDDEN:
        layers.append(ResidualBlock(prev, h))
        prev = h
    pca = torch.nn.Linear(PCA_DIM, features)
    with torch.no_grad():
        pca.weight.copy_(basis)
        pca.bias.copy_(mean)
    net = torch.nn.Sequential(*layers, torch.nn.Linear(prev, PCA_DIM), pca)
    net.eval()
    for p in net.parameters():
        p.requires_grad_(False)
    return net


def make_integrator(n_in):
    layers, prev = [], n_in
    for h in INTEGRATOR_HIDDEN:
        layers += [torch.nn.Linear(prev, h), torch.nn.SiLU()]
        prev = h
    layers.append(torch.nn.Linear(prev, LATENT))
    return torch.nn.Sequential(*layers)


def read_shell_dataset(path):
    """Mesh, masses, gravity, Dirichlet set, dt, material and sequences (positions, boundary
    parameters, train_frames) of a shell scene's `simulate` file: plotting_common.Dataset's
    reading and checks, plus the fields only the physics needs. Raises pc.InputError."""
    data = pc.Dataset(path)
    if data.object != "shell" or data.elements.shape[1] != 3:
        raise pc.InputError(f"'{path}' is not a shell scene (this loop implements the cloth's energies)")
    with pc.open_h5(path) as f:
        try:
            masses = np.asarray(f["masses"][()], dtype=float)
            gravity = np.asarray(f["gravity"][()], dtype=float)
            material = [float(f.attrs[k]) for k in ("youngs_modulus", "poisson_ratio", "thickness")]
            params = {key: np.asarray(f["sequences"][key]["bc_params"][()], dtype=float) for key, _ in data.sequences}
        except (KeyError, OSError, ValueError, TypeError) as exc:
            raise pc.InputError(f"'{path}' is not a latentbench shell dataset ({exc})") from None
    if masses.shape != (len(data.rest),):
        raise pc.InputError(f"'{path}': masses has shape {masses.shape}, expected ({len(data.rest)},)")
    seqs = [(data.ground_truth(key)[0], params[key], data.train_frames[key]) for key, _ in data.sequences]
    if not seqs:
        raise pc.InputError(f"'{path}' has no sequences")
    return data.rest, data.elements, masses, gravity, data.bc_indices, data.dt, material, seqs


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dataset", help="HDF5 dataset of a shell scene (latentbench simulate)")
    parser.add_argument("--epochs", type=int, default=30, help="timed epochs (default 30)")
    parser.add_argument("--warmup", type=int, default=3, help="untimed epochs first (default 3)")
    parser.add_argument("--threads", type=int, default=2, help="torch.set_num_threads (default 2)")
    parser.add_argument("--batch", type=int, default=256, help="batch size before the noisy copies (default 256)")
    parser.add_argument("--dtype", choices=["float32", "float64"], default="float32")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--check", action="store_true",
                        help="first check the energies at the dataset's Newton solutions")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    dtype = torch.float32 if args.dtype == "float32" else torch.float64

    pc.require_h5py()
    try:
        rest, triangles, masses, gravity, bc, dt, material, seqs = read_shell_dataset(args.dataset)
    except pc.InputError as exc:
        pc.fail(str(exc))
    shell = Shell(rest, triangles, *material)
    potential = Potential(shell, masses, gravity, dt, bc, dtype)
    N = rest.shape[0]

    if args.check:
        # Newton solutions: the free DOFs' gradient of the hard-BC potential vanishes there.
        pos = torch.as_tensor(seqs[0][0][2:200], dtype=torch.float64)
        prev, prev2 = (torch.as_tensor(seqs[0][0][a:b], dtype=torch.float64) for a, b in ((1, 199), (0, 198)))
        check = Potential(shell, masses, gravity, dt, bc, torch.float64)
        x = pos.clone().requires_grad_(True)
        check(x, 2.0 * prev - prev2, None).sum().backward()
        free = torch.ones(N, dtype=torch.bool)
        free[check.bc] = False
        residual = x.grad[:, free].norm(dim=(1, 2)).max().item()
        weight = float(np.linalg.norm(masses) * np.linalg.norm(gravity))
        print(f"energy check: max |free gradient| at 198 Newton solutions = {residual:.3e} "
              f"({residual / weight:.2e} × |M g|)")
        if not residual / weight < 1e-4:
            pc.fail(f"'{args.dataset}': the energies do not match the simulator's (gradient not ~0 at its solutions)")
        shell.to(dtype)

    # Samples: frames t = 2 .. train_frames − 1 of every sequence, BC-relative features.
    feats, params, tgts = [], [], []
    for positions, bc_params, train in seqs:
        P = positions[:train]
        targets = P[:, bc]
        feats.append((P - targets.mean(1, keepdims=True)).reshape(train, -1))
        params.append(bc_params[:train])
        tgts.append(targets)
    all_feats = np.concatenate(feats)
    mean = all_feats.mean(0)
    _, _, vt = np.linalg.svd(all_feats - mean, full_matrices=False)
    basis = vt[:PCA_DIM].T  # 3N × 50
    decoder = make_decoder(3 * N, torch.as_tensor(basis, dtype=dtype), torch.as_tensor(mean, dtype=dtype)).to(dtype)
    z_prev, z_prev2, z_target, p_in, targets_now, x1s, x2s = [], [], [], [], [], [], []
    for F, bp, T in zip(feats, params, tgts):
        Z = (F - mean) @ basis[:, :LATENT]  # latents: the first PCA coefficients (values do not matter)
        t = np.arange(2, F.shape[0])
        z_prev.append(Z[t - 1]), z_prev2.append(Z[t - 2]), z_target.append(Z[t])
        p_in.append(np.concatenate([bp[t], bp[t - 1], bp[t - 2]], 1))
        targets_now.append(T[t]), x1s.append(T[t - 1]), x2s.append(T[t - 2])
    as_t = lambda parts: torch.as_tensor(np.concatenate(parts), dtype=dtype)
    z_prev, z_prev2, p_in = as_t(z_prev), as_t(z_prev2), as_t(p_in)
    targets_now, targets_prev, targets_prev2 = as_t(targets_now), as_t(x1s), as_t(x2s)
    S = z_prev.shape[0]

    def decode(z, targets):
        return decoder(z).reshape(-1, N, 3) + targets.mean(1, keepdim=True)

    with torch.no_grad():  # the clean copies' decoded inputs, once (as latentbench caches them)
        X1_clean, X2_clean = decode(z_prev, targets_prev), decode(z_prev2, targets_prev2)

    def speeds(X1, X2):
        return ((X1 - X2).mean(1) / dt).norm(dim=-1)

    floor = max(BALANCING_FLOOR * speeds(X1_clean, X2_clean).mean().item(), 1e-12)
    inputs_all = torch.cat([z_prev, z_prev2, p_in], 1)
    in_mean, in_std = inputs_all.mean(0), inputs_all.std(0, unbiased=False).clamp_min(1e-12)
    out_scale = torch.ones(LATENT, dtype=dtype)
    integrator = make_integrator(inputs_all.shape[1]).to(dtype)
    adam = torch.optim.Adam(integrator.parameters(), lr=1e-3)
    batches = math.ceil(S / args.batch)

    def epoch():
        order = torch.as_tensor(rng.permutation(S))
        total = 0.0
        for chunk in torch.tensor_split(order, batches):
            n = chunk.numel()
            zp, zp2 = z_prev[chunk], z_prev2[chunk]
            noisy = []
            for z in (zp, zp2):
                a = NOISE_FRACTION * z.std(0, unbiased=False)
                noisy.append(z + a * (2.0 * torch.rand(n, LATENT, dtype=dtype) - 1.0))
            zp_all, zp2_all = torch.cat([zp, noisy[0]]), torch.cat([zp2, noisy[1]])
            p = p_in[chunk].repeat(2, 1)
            tn, tp, tp2 = (t[chunk].repeat(2, 1, 1) for t in (targets_now, targets_prev, targets_prev2))
            with torch.no_grad():
                X1 = torch.cat([X1_clean[chunk], decode(noisy[0], tp[n:])])
                X2 = torch.cat([X2_clean[chunk], decode(noisy[1], tp2[n:])])
                w = 1.0 / speeds(X1, X2).clamp_min(floor)
            inputs = (torch.cat([zp_all, zp2_all, p], 1) - in_mean) / in_std
            z = zp_all + out_scale * integrator(inputs)
            x = decode(z, tn)
            loss = (w * potential(x, 2.0 * X1 - X2, tn)).sum() / (2 * n)
            adam.zero_grad(set_to_none=True)
            loss.backward()
            adam.step()
            total += loss.item()
        return total

    for _ in range(args.warmup):
        epoch()
    times = []
    for _ in range(args.epochs):
        start = time.perf_counter()
        epoch()
        times.append(time.perf_counter() - start)
    times = np.array(times) * 1e3
    columns = 2 * S
    print(f"torch {torch.__version__}, {args.threads} threads, {args.dtype}: {S} samples, {batches} batches, "
          f"{columns} columns per epoch, {shell.triangles.shape[0]} triangles, {shell.hinges.shape[0]} hinges")
    print(f"epoch ms: median {np.median(times):.2f}  min {times.min():.2f}  max {times.max():.2f}  "
          f"(per 1,024 columns: median {np.median(times) * 1024 / columns:.2f}) over {args.epochs} epochs")


if __name__ == "__main__":
    main()
