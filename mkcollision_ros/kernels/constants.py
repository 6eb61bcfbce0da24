"""Iteration caps and tolerances of every iterative kernel, with their units.

Tolerances are relative to a length scale of the pair, ``scale`` (metres): the sum of
the two shapes' bounding radii.  Multiplying by the scale keeps a millimetre object and
a kilometre object equally well resolved.
"""

# --- shape codes, in the canonical pair order (a pair kernel has code_a <= code_b) ----
SPHERE = 0
ELLIPSOID = 1
BOX = 2
CAPSULE = 3
CYLINDER = 4
CONE = 5
CONVEX = 6
PLANE = 7
N_SHAPE_TYPES = 8
SHAPE_NAMES = ("sphere", "ellipsoid", "box", "capsule", "cylinder", "cone", "convex", "plane")

# --- layout of one row of the shape parameter table (float64[N_PARAMS]) ----------------
N_PARAMS = 8
P_GROUPS = 0     # convex: groups of its points, two rows each right after them in verts
                 # (0: none; mkcollision_ros.hull.support_groups, geometry._grouped_support)
P_FAN_FACES = 1  # convex: its hull's faces, edges and vertices stored after its points
P_FAN_EDGES = 2  # in verts for pairs/ellipsoid_convex.py (0 faces: none, and then maybe group rows;
P_FAN_VERTS = 3  # mkcollision_ros.hull.fan_rows has the layout)
FAN_MAX_POINTS = 64  # hulls of at most this many kept points get their fan (fan_rows): the
                     # exact kernel walks every face, edge and vertex, which pays against
                     # GJK/EPA only on small hulls, and fan_rows' builder is O(points^4)
P_ROLL = 3       # ellipsoid: radius of a ball that rolls freely inside it (m), see
                 # geometry.py (0 is always valid: the core is then the ellipsoid)
P_MARGIN = 6     # padding radius added around the shape (m)
P_RADIUS = 7     # bounding radius about the body origin, margin included (m)

# --- result status codes (see mkcollision_ros.results.Status) --------------------------
ST_SEPARATED = 0
ST_TOUCHING = 1
ST_PENETRATING = 2
ST_FAILED = 3
ST_NOT_RUN = 4

# --- method codes -----------------------------------------------------------------------
M_AUTO = 0
M_GJK_EPA = 1
M_MPR = 2
M_ANALYTIC = 3
M_ELLIPSOID_EXACT = 4
M_ELLIPSOID_SAMPLED = 5
METHOD_NAMES = ("auto", "gjk_epa", "mpr", "analytic", "ellipsoid_exact", "ellipsoid_sampled")

# --- the touching rule -------------------------------------------------------------------
# A pair is in contact iff signed distance <= TOUCH_TOL * scale.  |distance| within the
# tolerance is reported as TOUCHING, below it PENETRATING, above it SEPARATED.
TOUCH_TOL = 1e-9

# --- what a pair kernel run before GJK decided (pairs/; gjk_epa.gjk_epa_ws) -----------
# Each such kernel fills res (10,) = [h, normal (3), point on A (3), point on B (3)] in
# A's frame, on the cores (the shapes shrunk by their inflation radii), and returns one of:
PRE_UNDECIDED = -1         # nothing proved: GJK and EPA answer the pair
PRE_UNPROVED = 0           # (the fan kernels) no proof that the cores overlap: GJK runs, and
                           # once it finds them overlapping the kernel runs again in EPA's place
PRE_EXACT = 1              # res holds the cores' certified depth h > 0 or their exact distance
                           # -h >= 0, with the normal from A to B and the witness points
PRE_APART = 2              # a plane proves the cores farther apart than the caller's ``stop``
                           # (m): -h is that bound, res's points lie on the two cores

# --- batch kernel ------------------------------------------------------------------------
NP_CHUNK = 128             # fewest pairs per block of collide_batch (jit.n_blocks)

# --- GJK ---------------------------------------------------------------------------------
GJK_MAX_ITERS = 128        # iterations (support evaluations)
GJK_REL_TOL = 1e-12        # relative duality gap on the squared distance (dimensionless)
GJK_POLISH_TOL = 1e-3     # with an ellipsoid: try Newton's method once the gap < tol |v|^2
                           # (against 1e-4, deep ellipsoid pairs with their cores apart
                           # take 2-4% fewer GJK + EPA steps at 1e-3, fewer at 1e-2)
GJK_FLAT_TOL = 1e-9        # tetrahedra with 6|volume| <= tol * (longest edge)^3 are flat

# --- EPA ---------------------------------------------------------------------------------
EPA_MAX_ITERS = 255        # added vertices
EPA_MAX_FACES = 512        # face slots in the fixed polytope buffer
EPA_REL_TOL = 1e-8         # stop when support gain < tol * scale (dimensionless)
EPA_POLISH_TOL = 1e-3      # try Newton's method (polish_newton._epa_polish) once the support gain
                           # < tol * scale, and once more at 0.01 * tol * scale if it gave up
POLISH_STEP_DONE = 1e-6    # Newton's method and the crease search end once the step they
                           # would take next is below this (rad), at the point they are
                           # at: the direction is then within ~1e-6 rad of the minimum and
                           # h within ~1e-12 * scale of it.  That last step is not taken:
                           # it would cost a support for nothing the tolerances see
EPA_POLISH_ITERS = 6       # its steps (support evaluations)
EPA_POLISH_STEP = 0.05     # longest step it may take (rad)
EPA_POLISH_CAP = 0.5       # its minimum is kept only if no direction farther than this
                           # from its normal can be deeper by EPA's faces (rad;
                           # certificates._polish_is_global)
EPA_FACE_TOL = 1e-1         # test a box's face normal or a cylinder's axis within
                           # EPA_KINK_NEAR rad of EPA's best face normal for the minimum
                           # (polish_faces._face_polish) once the support gain < tol * scale
EPA_FACE_EVALS = 3         # at most this many supports for those tests per pair, in EPA
                           # and again in GJK on cores apart (gjk._gjk)
EPA_FACE_CAP_MAX = 1.5     # largest EPA_POLISH_CAP for a minimum found so (rad); the cap
                           # itself is proved by the test (certificates._face_basin)
EPA_KINK_NEAR = 0.05       # try the polish along a cylinder's side (polish_crease._kink_polish)
                           # when the best face's normal n has |n . axis| below this (a
                           # box: for one of its axes only; near two, n is near a face
                           # normal; 0.15 gives 2% more steps on deep ellipsoid-box pairs)
EPA_KINK_ITERS = 8         # its support evaluations
EPA_KINK_STEP = 0.1        # longest step it may take along the side's circle (rad)
EPA_KINK_CAP_CAPSULE = 0.05  # EPA_POLISH_CAP for a minimum on a capsule's crease (rad):
                           # deeper minima off it lie 0.09-0.19 rad away
EPA_KINK_CAP_BOX = 0.1     # and on a box edge's crease against an ellipsoid: at 0.5 rad,
                           # 1 of 100,000 random pairs keeps a minimum 3e-4 * scale too
                           # deep, the true one in a vertex's region 0.2 rad away (none
                           # at 0.1 or 0.05; 0.1 takes 18.1 steps, 0.05 18.8)
EPA_VERTEX_CAP_MIN = 0.05  # least basin cap for a box vertex's minimum against an ellipsoid
                           # (certificates._vertex_cap): its angle to the box's nearest crease

# --- MPR ---------------------------------------------------------------------------------
MPR_MAX_ITERS = 128        # portal refinements
MPR_REL_TOL = 1e-10        # portal-to-boundary gap, relative to scale

# --- exact ellipsoid distance ------------------------------------------------------------
ELL_MAX_ITERS = 200        # bisection steps on the Lagrange multiplier (float64 exhausts ~1100)

# --- layout of one pair result row (float64[OUT_SIZE]), every vector in A's frame or,
# after the batch kernel transforms it, in the world frame -------------------------------
OUT_DIST = 0       # signed distance (m): > 0 apart, < 0 penetrating (depth = -distance)
OUT_NORMAL = 1     # 1:4 unit normal from A to B; moving B by depth along it separates
OUT_PA = 4         # 4:7 witness point on A's surface
OUT_PB = 7         # 7:10 witness point on B's surface
OUT_ITERS = 10     # iterations used by the method
OUT_METHOD = 11    # method code (M_*)
OUT_SIZE = 12

# --- GJK / EPA extras (gjk_epa.py) -------------------------------------------------------
GJK_ABS_TOL = 1e-12        # stop GJK when the distance bound gap < tol * scale (dimensionless)
EPA_DEGEN_TOL = 1e-12      # flat Minkowski difference: volume/extent below tol * scale
EPA_WITNESS_SHIFT = 1e-7   # witness fix-up: B pulled apart by depth + shift * scale (m/m)
EPA_FAIL_GAP = 1e-4        # EPA caps hit: FAILED when upper - lower depth bound > tol * scale

# --- broad phase (broadphase.py) --------------------------------------------------------
PLANE_AXIS_TOL = 1e-12     # planes whose world normal has off-axis components below this
                           # are axis-aligned (dimensionless, components of a unit vector)

# --- pair kernels run before GJK (pairs/), in the canonical pair order ------------------
# ellipsoid-box (pairs/ellipsoid_box.py)
BE_POINT_ITERS = 40        # Newton steps on the Lagrange multiplier of a box vertex's
                           # nearest point on the ellipsoid (from t = 0, kept in the root's
                           # bracket; iterations)
BE_EXACT = 1e-12           # a distance is exact when its closest points are this much
                           # (times scale, dimensionless) farther apart than the separating
                           # plane's gap, at most
# ellipsoid-convex and cylinder-convex over a hull's normal fan (pairs/normal_fan.py,
# pairs/ellipsoid_convex.py, pairs/cylinder_convex.py)
HE_ITERS = 60              # cap of every 1-D root search (iterations)
HE_BALL_ITERS = 32         # cap of the GJK steps in E's unit-ball frame
                           # (ellipsoid_convex._unit_ball_test; cylinder_convex._cyl_gjk's
                           # too; iterations)
HE_BALL_TOL = 1e-9         # a point of B that far inside the unit ball proves overlap
                           # (relative to the unit ball, dimensionless)
HE_ROOT_RTOL = 1e-13       # a root's last Newton step (relative, dimensionless; the depth
                           # needs ~1e-10)
HE_DMIN_RTOL = 1e-12       # the search for phi's minimum between two poles gives up here
                           # (relative, dimensionless)
HE_SUPPORT_TOL = 1e-12     # a foot counts if B's support along -n is within this * scale
                           # (dimensionless)
HE_FOOT_SLACK = 1e-9       # normal_fan._plane_feet takes the right root for a point this
                           # far outside the ellipse too (relative, dimensionless): at
                           # touching the point lies on it, and rounding may put it just
                           # outside
HE_FAN_SLACK = 4e-10       # the edges' chord bound takes an edge's point on its faces'
                           # planes, within hull._FAN_TOL (1e-10) of the points' extent
                           # (<= 2 sqrt(3) radius_B), so it is lowered by this * scale
                           # (dimensionless)
# box-cylinder (pairs/box_cylinder.py)
BC_MAX_LEVEL = 4           # halvings of an arc whose bound is too low (then EPA; iterations)
BC_FEAT = 1e-9             # a box axis this close to normal to m: m is on its edge circle
                           # (|cosine|, dimensionless)
# the cylinder pairs (pairs/cylinder_common.py, cylinder_cylinder.py, cylinder_convex.py)
CC_NEWTON_ITERS = 8        # Newton steps on a rim's angle (~4 taken on average; iterations)
CC_HALF_TAN_MAX = 0.25     # longest step: tan of half its angle (dimensionless, ~0.49 rad);
                           # far from the minimum F'' may mislead
CC_HALF_TAN_DONE = 5e-5    # a step this short ends the search (tan of half its angle,
                           # dimensionless, 1e-4 rad; the angle's error is then of its
                           # square, and the ball's of its square)
CC_RIMS = 2                # rims solved at most, deepest bound first (measured on the
                           # benchmark's cases: 1 certifies 7% fewer pairs, 3 or 4 no more)
CC_COVER_STEPS = 12        # greedy steps of cylinder_common._cover at most (each raises the
                           # level covered; iterations)
CC_CROSS_RINGS = 16        # rings of cylinder_cylinder._crossing_global at most (measured:
                           # 8 certify 14 fewer of 965 crossings, 30 two more)
HC_GJK_ITERS = 16          # steps of the 2-D GJK on a hull's shadow
                           # (cylinder_convex.collide_cylinder_convex_ball, ~4 taken;
                           # iterations)

# --- contact manifold (manifold.py) and persistence (persistence.py) --------------------
FACE_SIN = 0.05            # sin of the angle (~2.9 deg) within which a cap / side is a face
                           # (dimensionless)
FACE_SLACK = 0.05          # convex hull face tolerance, relative to the hull's diameter
                           # (dimensionless)
REF_COS = 0.9              # the reference face normal must be within ~26 deg of n (cosine,
                           # dimensionless)
# the reduction to max_contacts (persistence._reduce) treats as equal, and gives to the
# older contact: depths within DEPTH_TIE x merge_distance (dimensionless), squared
# distances and areas within REDUCE_TIE of the largest (relative, dimensionless)
DEPTH_TIE = 1e-3
REDUCE_TIE = 1e-3
