"""The cart-pendulum plant: parameters, nonlinear and linear equations, one integration step."""
