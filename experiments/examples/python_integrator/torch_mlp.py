"""An MLP latent integrator trained in PyTorch on latentbench's own physics, as a latentbench
method (``method = "python"``). Needs python3-torch (not a latentbench dependency).

    z_t = z_{t-1} + MLP([z_{t-1}, z_{t-2}, p_t, p_{t-1}, p_{t-2}])

The loss is the paper's self-supervised one without noise or balancing: the incremental
potential E(D(z_t); D(z_{t-1}), D(z_{t-2})) of the decoded prediction, with its latent gradient
from ``latentbench.LatentPotential`` (the scene's energy, autoencoder and Dirichlet penalty),
back-propagated through the MLP by a ``torch.autograd.Function``. The interface is in
docs/python.md, "Python integrators".
"""
import numpy as np
import torch

import latentbench as lb


class _LatentEnergy(torch.autograd.Function):
    """Sum over the batch of E(D(z_i)), gradients from latentbench (float64, on the CPU)."""

    @staticmethod
    def forward(ctx, z, potential, targets, x_prev, x_prev2):
        zs = z.detach().numpy()
        grads = np.empty_like(zs)
        total = 0.0
        for i in range(zs.shape[0]):
            e, g = potential.value_and_gradient(zs[i], targets[i], x_prev[i], x_prev2[i])
            total += e
            grads[i] = g
        ctx.save_for_backward(torch.from_numpy(grads))
        return z.new_tensor(total)

    @staticmethod
    def backward(ctx, grad_output):
        (grads,) = ctx.saved_tensors
        return grad_output * grads, None, None, None, None


class TorchPhysicsMlp:
    def __init__(self, hidden=(64, 64), epochs=200, learning_rate=1e-3, batch=128, penalty_weight=1e5):
        self.hidden = [int(h) for h in hidden]
        self.epochs, self.learning_rate = int(epochs), float(learning_rate)
        self.batch, self.penalty_weight = int(batch), float(penalty_weight)
        self.net = None

    def _make(self, n_in, n_out):
        layers, width = [], n_in
        for h in self.hidden:
            layers += [torch.nn.Linear(width, h), torch.nn.SiLU()]
            width = h
        layers.append(torch.nn.Linear(width, n_out))
        return torch.nn.Sequential(*layers).double()

    def fit(self, data, seed):
        if data.dataset_path is None or data.autoencoder_path is None:
            raise ValueError("needs the dataset and autoencoder files (run it from a suite or `fit --ae`)")
        torch.manual_seed(seed)
        rng = np.random.default_rng(seed)
        dataset = lb.Dataset.load(data.dataset_path)
        physics = lb.Physics(dataset)
        ae = lb.Autoencoder.load(data.autoencoder_path, physics)
        potential = lb.LatentPotential(physics, ae, self.penalty_weight)
        feats, z_prev, targets, x_prev, x_prev2 = [], [], [], [], []
        for z, p, b in zip(data.latents, data.params, data.targets):
            decoded = ae.decode(z.T, b.T).T  # the histories, decoded as in a rollout
            for t in range(2, len(z)):
                feats.append(np.concatenate([z[t - 1], z[t - 2], p[t], p[t - 1], p[t - 2]]))
                z_prev.append(z[t - 1])
                targets.append(b[t])
                x_prev.append(decoded[t - 1])
                x_prev2.append(decoded[t - 2])
        X = np.array(feats)
        self.mean, self.std = X.mean(0), X.std(0) + 1e-12
        Xs = torch.from_numpy((X - self.mean) / self.std)
        Zp = torch.from_numpy(np.array(z_prev))
        targets, x_prev, x_prev2 = np.array(targets), np.array(x_prev), np.array(x_prev2)
        self.net = self._make(X.shape[1], Zp.shape[1])
        opt = torch.optim.Adam(self.net.parameters(), lr=self.learning_rate)
        for _ in range(self.epochs):
            order = rng.permutation(len(X))
            for start in range(0, len(X), self.batch):
                idx = order[start:start + self.batch]
                z = Zp[idx] + self.net(Xs[idx])
                loss = _LatentEnergy.apply(z, potential, targets[idx], x_prev[idx], x_prev2[idx]) / len(idx)
                opt.zero_grad()
                loss.backward()
                opt.step()
        arrays = {k.replace(".", "-"): v.detach().numpy() for k, v in self.net.state_dict().items()}
        arrays.update(mean=self.mean, std=self.std, shape=np.array([X.shape[1], Zp.shape[1]]))
        return arrays

    def load(self, arrays):
        n_in, n_out = (int(v) for v in arrays["shape"])
        self.net = self._make(n_in, n_out)
        state = {k.replace("-", "."): torch.from_numpy(v) for k, v in arrays.items() if k not in ("mean", "std", "shape")}
        self.net.load_state_dict(state)
        self.mean, self.std = arrays["mean"], arrays["std"]

    def reset(self, z_prev2, z_prev, p_prev2, p_prev):
        self.z2, self.z1, self.p2, self.p1 = z_prev2, z_prev, p_prev2, p_prev

    def step(self, p):
        x = (np.concatenate([self.z1, self.z2, p, self.p1, self.p2]) - self.mean) / self.std
        with torch.no_grad():
            z = self.z1 + self.net(torch.from_numpy(x)).numpy()
        self.z2, self.z1, self.p2, self.p1 = self.z1, z, self.p1, p
        return z
