"""A linear latent integrator in NumPy, as a latentbench method (``method = "python"``).

    z_t = z_{t-1} + W^T [z_{t-1}, z_{t-2}, p_t, p_{t-1}, 1]

W is fitted by ridge least squares on the training frames' latents (encoded by the scene's
autoencoder, the same data every method gets). The suite file beside this one puts it next
to the paper's integrator on the small cloth. The interface is in docs/python.md, "Python
integrators".
"""
import numpy as np


class LinearLatentMap:
    def __init__(self, ridge=1e-6):
        self.ridge = float(ridge)
        self.W = None

    @staticmethod
    def _features(z_prev, z_prev2, p, p_prev):
        return np.concatenate([z_prev, z_prev2, p, p_prev, [1.0]])

    def fit(self, data, seed):
        rows, targets = [], []
        for z, p in zip(data.latents, data.params):
            for t in range(2, len(z)):
                rows.append(self._features(z[t - 1], z[t - 2], p[t], p[t - 1]))
                targets.append(z[t] - z[t - 1])
        X, Y = np.array(rows), np.array(targets)
        # The ridge is relative to the features' scale, so it means the same on every scene.
        lam = self.ridge * np.trace(X.T @ X) / X.shape[1]
        W = np.linalg.solve(X.T @ X + lam * np.eye(X.shape[1]), X.T @ Y)
        return {"W": W}

    def load(self, arrays):
        self.W = arrays["W"]

    def reset(self, z_prev2, z_prev, p_prev2, p_prev):
        self.z_prev2, self.z_prev, self.p_prev = z_prev2, z_prev, p_prev

    def step(self, p):
        z = self.z_prev + self._features(self.z_prev, self.z_prev2, p, self.p_prev) @ self.W
        self.z_prev2, self.z_prev, self.p_prev = self.z_prev, z, p
        return z
