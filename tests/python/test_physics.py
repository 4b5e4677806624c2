"""The physics for prototypes against finite differences: the incremental potential's
gradient (with and without the Dirichlet penalty), the decoder's vector-Jacobian product and
the one-call E(D(z)) latent gradient; and E(D(z)) equals the potential of the decoded state."""
import numpy as np
import pytest

import latentbench as lb


@pytest.fixture(scope="module")
def setup(cloth):
    data = lb.Dataset.load(str(cloth["data"]))
    physics = lb.Physics(data)
    ae = lb.Autoencoder.load(str(cloth["ae"]), physics)
    seq = data.sequences[0]
    return data, physics, ae, seq


def central_difference(f, x, v, h):
    return (f(x + h * v) - f(x - h * v)) / (2 * h)


def test_potential_gradient_matches_finite_differences(setup):
    data, physics, ae, seq = setup
    rng = np.random.default_rng(0)
    t = 10
    x_prev2, x_prev = seq.positions[t - 2].copy(), seq.positions[t - 1].copy()
    # A state off the trajectory, so that every term (inertia, elasticity) has a gradient.
    x = seq.positions[t] + 1e-3 * rng.standard_normal(physics.num_dofs)
    targets = seq.bc_positions[t] + 1e-3 * rng.standard_normal(seq.bc_positions.shape[1])
    for kwargs in ({}, {"bc_targets": targets, "penalty_weight": 1e4}):
        f = lambda y: physics.potential(y, x_prev, x_prev2, **kwargs)
        e, g = physics.potential_and_gradient(x, x_prev, x_prev2, **kwargs)
        assert e == pytest.approx(f(x), rel=1e-12)  # one pass over the elements or two
        assert g.shape == (physics.num_dofs,)
        for _ in range(5):
            v = rng.standard_normal(physics.num_dofs)
            v /= np.linalg.norm(v)
            fd = central_difference(f, x, v, 1e-6)
            assert abs(fd - g @ v) <= 1e-5 * max(1.0, abs(fd)) + 1e-6 * np.linalg.norm(g), (kwargs.keys(), fd, g @ v)
    # The penalty adds w Σ_B |x_i − x*_i|² exactly.
    e0 = physics.potential(x, x_prev, x_prev2)
    e1 = physics.potential(x, x_prev, x_prev2, bc_targets=targets, penalty_weight=1e4)
    xb = x.reshape(-1, 3)[physics.bc_indices].ravel()
    assert e1 - e0 == pytest.approx(1e4 * np.sum((xb - targets) ** 2), rel=1e-9, abs=1e-12)


def test_decoder_vjp_matches_finite_differences(setup):
    data, physics, ae, seq = setup
    rng = np.random.default_rng(1)
    bc = seq.bc_positions[8].copy()
    z = ae.encode(seq.positions[8])
    w = rng.standard_normal(physics.num_dofs)  # the loss w · D(z)
    grad = ae.vjp(z, w, bc)
    assert grad.shape == (ae.latent_dim,)
    for k in range(ae.latent_dim):
        e = np.zeros(ae.latent_dim)
        e[k] = 1.0
        fd = central_difference(lambda y: w @ ae.decode(y, bc), z, e, 1e-6)
        assert fd == pytest.approx(grad[k], rel=1e-5, abs=1e-7 * np.linalg.norm(grad))
    # Batched calls agree with one column at a time.
    Z = np.stack([z, z + 0.1], axis=1)
    B = np.stack([bc, bc], axis=1)
    assert np.allclose(ae.decode(Z, B)[:, 1], ae.decode(z + 0.1, bc), rtol=0, atol=1e-14)


def test_latent_energy_gradient_matches_finite_differences(setup):
    data, physics, ae, seq = setup
    t = 12
    bc, x_prev, x_prev2 = seq.bc_positions[t], seq.positions[t - 1], seq.positions[t - 2]
    z = ae.encode(seq.positions[t]) + 0.01
    e, g = lb.latent_energy(physics, ae, z, bc, x_prev, x_prev2, penalty_weight=1e4)
    # E(D(z)) is the full-space potential of the decoded state, penalty included.
    x = ae.decode(z, bc)
    assert e == pytest.approx(physics.potential(x, x_prev, x_prev2, bc_targets=bc, penalty_weight=1e4), rel=1e-12)
    potential = lb.LatentPotential(physics, ae, penalty_weight=1e4)
    f = lambda y: potential.value_and_gradient(y, bc, x_prev, x_prev2)[0]
    for k in range(ae.latent_dim):
        d = np.zeros(ae.latent_dim)
        d[k] = 1.0
        fd = central_difference(f, z, d, 1e-6)
        assert fd == pytest.approx(g[k], rel=1e-5, abs=1e-6 * np.linalg.norm(g)), k
    # The chain rule through the two other bindings gives the same gradient.
    _, gx = physics.potential_and_gradient(x, x_prev, x_prev2, bc_targets=bc, penalty_weight=1e4)
    assert np.allclose(ae.vjp(z, gx, bc), g, rtol=1e-10, atol=1e-12 * np.linalg.norm(g))


def test_wrong_shapes_are_refused(setup):
    data, physics, ae, seq = setup
    x = seq.positions[3]
    with pytest.raises(lb.Error, match="x_prev: expected"):
        physics.potential(x, x[:-3], x)
    with pytest.raises(lb.Error, match="bc_targets: required"):
        physics.potential(x, x, x, penalty_weight=1.0)
    with pytest.raises(lb.Error, match="z: expected"):
        ae.decode(np.zeros(ae.latent_dim + 1), seq.bc_positions[3])


def test_physics_from_the_scene_file_equals_the_datasets(setup):
    data, physics, ae, seq = setup
    from conftest import CLOTH
    scene = lb.Physics.from_scene(str(CLOTH), "small")
    assert scene.num_dofs == physics.num_dofs and scene.bc_indices == physics.bc_indices
    x, x1, x2 = seq.positions[6], seq.positions[5], seq.positions[4]
    assert scene.potential(x, x1, x2) == physics.potential(x, x1, x2)
    with pytest.raises(lb.Error, match="nope"):
        lb.Physics.from_scene(str(CLOTH), "nope")
