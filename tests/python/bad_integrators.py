"""Python integrators that break the method interface on purpose (test_python_integrators.py):
each must get a clear error naming its class, the call and the frame."""
import numpy as np


class _Base:
    def fit(self, data, seed):
        return {"d": np.array([data.latents[0].shape[1]])}

    def load(self, arrays):
        self.d = int(arrays["d"][0])

    def reset(self, z_prev2, z_prev, p_prev2, p_prev):
        self.z = z_prev

    def step(self, p):
        return self.z


class RaisesInStep(_Base):
    def step(self, p):
        return 1 / 0


class WrongShape(_Base):
    def step(self, p):
        return np.zeros(self.d + 2)


class ReturnsNaN(_Base):
    def step(self, p):
        return np.full(self.d, np.nan)


class RaisesInFit(_Base):
    def fit(self, data, seed):
        raise RuntimeError("no training data I like")


class NotADict(_Base):
    def fit(self, data, seed):
        return [1, 2, 3]


class ExitsTheProcess(_Base):
    def step(self, p):
        import os
        os._exit(3)
