"""The regressor Phi = d/dr_G [M vartheta + C(nu) nu + g_G(eta)] (docs/model.md sec. 3.1)."""
from derive.symbols import nu, r_G, vartheta


def regressor(body):
    """6x3 matrix; exact because M, C and g_G are affine in r_G."""
    return (body.M * vartheta + body.C * nu + body.g_G).jacobian(r_G)
