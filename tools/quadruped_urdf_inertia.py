#!/usr/bin/env python3
"""The base_inertia link of models/wheeled_quadruped.urdf: what remains of the base body of
tests/models/quadruped.yaml (40 kg, centre of mass (0.02, 0, 0.01), principal moments 0.4, 1.2,
1.4 kg*m^2 about axes pitched by 0.05 rad) once the IMU and the lidar, fixed to the base as
separate links, are taken out. Written independently of wlx-gen (plain Python, no wlx code), so
that the URDF test compares wlx-gen's merge of fixed links with the hand-written base."""
import math


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def rpy(roll, pitch, yaw):  # URDF: R = Rz(yaw) Ry(pitch) Rx(roll)
    cr, sr, cp, sp, cy, sy = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw), math.sin(yaw)
    rz = [[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]]
    ry = [[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]]
    rx = [[1, 0, 0], [0, cr, -sr], [0, sr, cr]]
    return matmul(rz, matmul(ry, rx))


def diag(a, b, c):
    return [[a, 0, 0], [0, b, 0], [0, 0, c]]


def steiner(m, d):  # m (|d|^2 E - d d^T)
    n = sum(x * x for x in d)
    return [[m * ((n if i == j else 0) - d[i] * d[j]) for j in range(3)] for i in range(3)]


def add(a, b, s=1.0):
    return [[a[i][j] + s * b[i][j] for j in range(3)] for i in range(3)]


# The whole base (tests/models/quadruped.yaml).
mass, com = 40.0, [0.02, 0.0, 0.01]
turn = rpy(0, 0.05, 0)
inertia = matmul(turn, matmul(diag(0.4, 1.2, 1.4), transpose(turn)))

# The parts fixed to it: (mass, joint xyz, joint rpy, inertial xyz, inertial rpy, principal moments).
parts = {
    "imu_link": (0.1, [0.15, 0.02, 0.05], (math.pi, 0, 0), [0, 0, 0.005], (0, 0, 0), (1e-4, 1e-4, 2e-4)),
    "lidar": (0.9, [0.25, 0.0, 0.12], (0, 0.2, 0), [0, 0, 0.03], (0, 0, 0), (0.0012, 0.0012, 0.0015)),
}
rest_mass, rest_moment = mass, [mass * x for x in com]
placed = []
for name, (m, xyz, angles, cxyz, crpy, moments) in parts.items():
    r = rpy(*angles)
    c = [xyz[i] + sum(r[i][k] * cxyz[k] for k in range(3)) for i in range(3)]
    rc = matmul(r, rpy(*crpy))
    placed.append((m, c, matmul(rc, matmul(diag(*moments), transpose(rc)))))
    rest_mass -= m
    rest_moment = [rest_moment[i] - m * c[i] for i in range(3)]
rest_com = [x / rest_mass for x in rest_moment]
rest = add(inertia, steiner(mass, [com[i] - rest_com[i] for i in range(3)]))  # the whole, about rest_com
for m, c, i_c in placed:
    rest = add(rest, add(i_c, steiner(m, [c[i] - rest_com[i] for i in range(3)])), -1.0)
print(f'mass value="{rest_mass!r}"')
print('origin xyz="{}"'.format(" ".join(repr(x) for x in rest_com)))
print(f'inertia ixx="{rest[0][0]!r}" ixy="{rest[0][1]!r}" ixz="{rest[0][2]!r}" iyy="{rest[1][1]!r}" iyz="{rest[1][2]!r}" izz="{rest[2][2]!r}"')
