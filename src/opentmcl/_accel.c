/* opentmcl._accel: an optional compiled twin of the virtual module's request path.

   Three pieces, each the exact equivalent of a pure-Python reference that stays the
   definition (src/opentmcl/accel.py says how the firmware uses them, docs/performance.md
   "Compiled accelerator"):

   - Handle(vm): `VirtualModule.handle` (firmware/vm.py) as a callable object. The fast path
     looks the frame up in `vm._requests`, restarts the heartbeat and syncs the engines when
     virtual time moved; everything else goes to `vm._handle_general(frame, interface)`.
     Every attribute of the vm is read on every call (the vm rebinds them); only the vm is held.
     When type(vm).handle is no longer the method it was built under (patched onto the class,
     vm.__class__ reassigned), that method answers instead; __reduce__ rebuilds it on a copy.
   - packed(head, read, slow): `dispatch._packed(head, read)`: the 9-byte reply (TMCM-6212
     manual 3.2) of `read()` behind four fixed bytes, the value wrapped to 32 bits, the
     checksum. `slow(value)` answers values that are not Python ints (the Python code path).
   - sixpoint_read(engine, which, fallback): `SixPointRampEngine.position` (which 0) or
     `.position_reached` (which 1) evaluated from the engine's segment in 128-bit integers;
     any state outside the plain case (an operand or a result beyond 128 bits, a segment
     that has ended, an unexpected shape) calls `fallback()`, the Python property.
*/
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#include <stdint.h>

/* ---------------------------------------------------------------------------------------- */
/* interned names                                                                           */

static PyObject *s_requests, *s_last_command, *s_now, *s_heartbeat_fired, *s_synced_at;
static PyObject *s_sync_engines, *s_handle_general, *s_serial, *s_interface, *s_handle;
static PyObject *s_queue, *s_pieces;
static PyObject *s_target, *s_target_abs, *s_advance;
static PyObject *heartbeat_of;  /* the table of vm._HEARTBEAT_OF: link -> heartbeat name */

static int
intern_names(void)
{
#define NAME(var, text) if (!((var) = PyUnicode_InternFromString(text))) return -1
    NAME(s_requests, "_requests");
    NAME(s_last_command, "_last_command");
    NAME(s_now, "now");
    NAME(s_heartbeat_fired, "_heartbeat_fired");
    NAME(s_synced_at, "_synced_at");
    NAME(s_sync_engines, "_sync_engines");
    NAME(s_handle_general, "_handle_general");
    NAME(s_serial, "serial");
    NAME(s_interface, "interface");
    NAME(s_handle, "handle");
    NAME(s_queue, "_queue");
    NAME(s_pieces, "pieces");
    NAME(s_target, "_target");
    NAME(s_target_abs, "_target_abs");
    NAME(s_advance, "advance");
#undef NAME
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* the reply (manual 3.2): four head bytes, the value MSB first, the checksum               */

static PyObject *
reply9(const unsigned char *head, unsigned int head_sum, uint32_t value)
{
    unsigned char out[9];
    out[0] = head[0];
    out[1] = head[1];
    out[2] = head[2];
    out[3] = head[3];
    out[4] = (unsigned char)(value >> 24);
    out[5] = (unsigned char)(value >> 16);
    out[6] = (unsigned char)(value >> 8);
    out[7] = (unsigned char)value;
    out[8] = (unsigned char)((head_sum + out[4] + out[5] + out[6] + out[7]) & 0xFF);
    return PyBytes_FromStringAndSize((const char *)out, 9);
}

/* ---------------------------------------------------------------------------------------- */
/* six-point engine reads                                                                   */

#ifdef __SIZEOF_INT128__
#define HAVE_INT128 1
typedef __int128 i128;
typedef unsigned __int128 u128;
/* PSCALE = 2 * DEN = 2^42 * 5^12 (motion/segments.py): position units per microstep */
#define PSCALE ((i128)4398046511104LL * (i128)244140625LL)
#else
#define HAVE_INT128 0
#endif

enum { READ_POSITION = 0, READ_REACHED = 1 };
enum { R_VALUE = 0, R_FALLBACK = 1, R_ERROR = -1 };

#if HAVE_INT128
static PyObject *sixty_four;

/* a Python int as a 128-bit integer: 0; 1 when it is no exact int or does not fit (the caller
   falls back); -1 with an exception set */
static int
to_i128(PyObject *obj, i128 *out)
{
    int overflow;
    long long small;

    if (!PyLong_CheckExact(obj))
        return 1;
    small = PyLong_AsLongLongAndOverflow(obj, &overflow);
    if (!overflow) {
        if (small == -1 && PyErr_Occurred())
            return -1;
        *out = small;
        return 0;
    }
    {
        /* 16 bytes of two's complement, little-endian: no intermediate int */
        unsigned char buf[16];
        u128 u = 0;
        int i;
#if PY_VERSION_HEX >= 0x030D0000
        Py_ssize_t n = PyLong_AsNativeBytes(obj, buf, 16, Py_ASNATIVEBYTES_LITTLE_ENDIAN);
        if (n < 0)
            return -1;
        if (n > 16)
            return 1;  /* does not fit */
#else
        if (_PyLong_AsByteArray((PyLongObject *)obj, buf, 16, 1, 1) < 0) {
            if (!PyErr_ExceptionMatches(PyExc_OverflowError))
                return -1;
            PyErr_Clear();
            return 1;  /* does not fit */
        }
#endif
        for (i = 15; i >= 0; i--)
            u = (u << 8) | buf[i];
        *out = (i128)u;
    }
    return 0;
}

/* floor(p / PSCALE) (backwards 0) or ceil(p / PSCALE) (backwards 1) */
static i128
step_of(i128 p, int backwards)
{
    i128 q = p / PSCALE, r = p % PSCALE;
    if (r != 0) {
        if (backwards) {
            if (r > 0)
                q += 1;
        }
        else if (r < 0) {
            q -= 1;
        }
    }
    return q;
}

static long long
wrap32(i128 q)
{
    uint32_t u = (uint32_t)(u128)q;
    return u >= 0x80000000u ? (long long)u - 0x100000000LL : (long long)u;
}

/* attribute as i128: 0 ok, 1 fall back, -1 error */
static int
attr_i128(PyObject *obj, PyObject *name, i128 *out)
{
    PyObject *v = PyObject_GetAttr(obj, name);
    int rc;
    if (!v) {
        PyErr_Clear();  /* the Python property raises it again, or knows better */
        return 1;
    }
    rc = to_i128(v, out);
    Py_DECREF(v);
    return rc;
}

/* The state of `engine` at its tick `now`: the first queued piece (k0, k1, p0, v0, a)
   when it holds now; 1 when the Python property must answer. */
typedef struct {
    i128 now, k0, p0, v0, a;
    PyObject *pieces;  /* borrowed through the queue, kept by `queue_ref` */
} piece_state;

/* A read's copy of the segment it last converted: a segment is a tuple (immutable), so while
   the queue's first piece is that very object, its values are these. */
typedef struct {
    PyObject *seg;  /* a strong reference, or NULL */
    i128 k0, k1, p0, v0, a;
    int has_k1;
} segment_cache;

/* convert `seg` into `c`: 0 ok; 1 fall back or -1 error, `c` unchanged */
static int
convert_segment(PyObject *seg, segment_cache *c)
{
    int rc;
    segment_cache t;
    PyObject *k1 = PyTuple_GET_ITEM(seg, 1);
    t.has_k1 = k1 != Py_None;
    t.k1 = 0;
    if (t.has_k1 && (rc = to_i128(k1, &t.k1)) != 0)
        return rc;
    if ((rc = to_i128(PyTuple_GET_ITEM(seg, 0), &t.k0)) != 0
        || (rc = to_i128(PyTuple_GET_ITEM(seg, 2), &t.p0)) != 0
        || (rc = to_i128(PyTuple_GET_ITEM(seg, 3), &t.v0)) != 0
        || (rc = to_i128(PyTuple_GET_ITEM(seg, 4), &t.a)) != 0)
        return rc;
    Py_INCREF(seg);
    t.seg = c->seg;
    *c = t;
    c->seg = seg;
    Py_XDECREF(t.seg);  /* the segment converted before */
    return 0;
}

static int
engine_piece(PyObject *engine, piece_state *st, PyObject **queue_ref, segment_cache *c)
{
    PyObject *queue, *pieces, *seg;
    int rc;

    *queue_ref = NULL;
    if ((rc = attr_i128(engine, s_now, &st->now)) != 0)
        return rc;
    queue = PyObject_GetAttr(engine, s_queue);
    if (!queue) {
        PyErr_Clear();
        return 1;
    }
    pieces = PyObject_GetAttr(queue, s_pieces);
    Py_DECREF(queue);
    if (!pieces) {
        PyErr_Clear();
        return 1;
    }
    *queue_ref = pieces;
    st->pieces = pieces;
    if (!PyList_CheckExact(pieces) || PyList_GET_SIZE(pieces) < 1)
        return 1;
    seg = PyList_GET_ITEM(pieces, 0);
    if (!PyTuple_Check(seg) || PyTuple_GET_SIZE(seg) != 6)
        return 1;
    if (seg != c->seg && (rc = convert_segment(seg, c)) != 0)
        return rc;
    if (c->has_k1 && c->k1 <= st->now)
        return 1;  /* a piece that has ended: SegmentQueue.at finds the one holding now */
    st->k0 = c->k0;
    st->p0 = c->p0;
    st->v0 = c->v0;
    st->a = c->a;
    return 0;
}

/* the wrapped step counter at now (sixpoint._read): 0 ok, 1 fall back */
static int
position_at(const piece_state *st, long long *pos)
{
    i128 dt, t, p;
    int backwards;
    if (st->v0 == 0 && st->a == 0) {
        *pos = wrap32(step_of(st->p0, 0));
        return 0;
    }
    if (__builtin_sub_overflow(st->now, st->k0, &dt)
        || __builtin_mul_overflow(st->a, dt, &t)
        || __builtin_add_overflow(t, st->v0, &t)
        || __builtin_add_overflow(t, st->v0, &t)       /* 2 * v0 + a * dt */
        || __builtin_mul_overflow(t, dt, &t)
        || __builtin_add_overflow(t, st->p0, &p))
        return 1;
    backwards = st->v0 ? st->v0 < 0 : st->a < 0;
    *pos = wrap32(step_of(p, backwards));
    return 0;
}

/* attribute as a long long: 0 ok, 1 fall back */
static int
attr_ll(PyObject *obj, PyObject *name, long long *out)
{
    i128 v;
    int rc = attr_i128(obj, name, &v);
    if (rc < 0) {
        PyErr_Clear();
        return 1;
    }
    if (rc || v > INT64_MAX || v < INT64_MIN)
        return 1;
    *out = (long long)v;
    return 0;
}

static int
reached_at(PyObject *engine, const piece_state *st, long long *out)
{
    long long target, pos;
    i128 v, target_abs, scaled;
    if (st->v0 == 0 && st->a == 0) {
        if (attr_ll(engine, s_target, &target))
            return 1;
        if (attr_i128(engine, s_target_abs, &target_abs) != 0) {
            PyErr_Clear();
            return 1;
        }
        if (__builtin_mul_overflow(target_abs, PSCALE, &scaled))
            return 1;
        *out = st->p0 == scaled || wrap32(step_of(st->p0, 0)) == target;
        return 0;
    }
    if (__builtin_sub_overflow(st->now, st->k0, &v) || __builtin_mul_overflow(v, st->a, &v)
        || __builtin_add_overflow(v, st->v0, &v))
        return 1;
    if (v != 0) {  /* moving: no target read, as the property's `and` */
        *out = 0;
        return 0;
    }
    if (attr_ll(engine, s_target, &target) || position_at(st, &pos))
        return 1;
    *out = pos == target;
    return 0;
}

/* the read `which` of the engine as a C value: R_VALUE, R_FALLBACK or R_ERROR */
static int
sixpoint_value(PyObject *engine, int which, long long *out, segment_cache *c)
{
    piece_state st;
    PyObject *pieces = NULL;
    int rc = engine_piece(engine, &st, &pieces, c);
    if (rc == 0) {
        /* the closed form of the piece holding now, as the property's lazy read (`_read`)
           evaluates it: its cache, when current, holds these same values */
        if (which == READ_POSITION)
            rc = position_at(&st, out);
        else
            rc = reached_at(engine, &st, out);
    }
    Py_XDECREF(pieces);
    if (rc < 0) {
        PyErr_Clear();
        rc = 1;
    }
    return rc ? R_FALLBACK : R_VALUE;
}
#endif /* HAVE_INT128 */

/* ---------------------------------------------------------------------------------------- */
/* SixPointRead                                                                             */

typedef struct {
    PyObject_HEAD
    PyObject *engine;
    PyObject *fallback;
    int which;
    vectorcallfunc vectorcall;
#if HAVE_INT128
    segment_cache cache;
#endif
} SixPointReadObject;

static PyTypeObject SixPointReadType;

/* the value of a read: a new reference */
static PyObject *
sixpoint_call_value(SixPointReadObject *self)
{
#if HAVE_INT128
    long long v;
    if (sixpoint_value(self->engine, self->which, &v, &self->cache) == R_VALUE) {
        if (self->which == READ_REACHED)
            return PyBool_FromLong((long)v);
        return PyLong_FromLongLong(v);
    }
#endif
    return PyObject_CallNoArgs(self->fallback);
}

static PyObject *
sixpoint_vectorcall(PyObject *callable, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    (void)args;
    if (PyVectorcall_NARGS(nargsf) != 0 || (kwnames && PyTuple_GET_SIZE(kwnames))) {
        PyErr_SetString(PyExc_TypeError, "a six-point read takes no arguments");
        return NULL;
    }
    if (!((SixPointReadObject *)callable)->engine || !((SixPointReadObject *)callable)->fallback) {
        PyErr_SetString(PyExc_ReferenceError, "the six-point read was cleared");  /* by the GC */
        return NULL;
    }
    return sixpoint_call_value((SixPointReadObject *)callable);
}

static int
sixpoint_traverse(SixPointReadObject *self, visitproc visit, void *arg)
{
    Py_VISIT(self->engine);
    Py_VISIT(self->fallback);
#if HAVE_INT128
    Py_VISIT(self->cache.seg);
#endif
    return 0;
}

static int
sixpoint_clear(SixPointReadObject *self)
{
    Py_CLEAR(self->engine);
    Py_CLEAR(self->fallback);
#if HAVE_INT128
    Py_CLEAR(self->cache.seg);
#endif
    return 0;
}

static void
sixpoint_dealloc(SixPointReadObject *self)
{
    PyObject_GC_UnTrack(self);
    sixpoint_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *
sixpoint_read(PyObject *module, PyObject *args)
{
    PyObject *engine, *fallback;
    int which;
    SixPointReadObject *self;
    (void)module;
    if (!PyArg_ParseTuple(args, "OiO:sixpoint_read", &engine, &which, &fallback))
        return NULL;
    if (which != READ_POSITION && which != READ_REACHED) {
        PyErr_SetString(PyExc_ValueError, "which must be 0 (position) or 1 (position_reached)");
        return NULL;
    }
    if (!PyCallable_Check(fallback)) {
        PyErr_SetString(PyExc_TypeError, "fallback must be callable");
        return NULL;
    }
    self = PyObject_GC_New(SixPointReadObject, &SixPointReadType);
    if (!self)
        return NULL;
    Py_INCREF(engine);
    Py_INCREF(fallback);
    self->engine = engine;
    self->fallback = fallback;
    self->which = which;
    self->vectorcall = sixpoint_vectorcall;
#if HAVE_INT128
    self->cache.seg = NULL;
#endif
    PyObject_GC_Track(self);
    return (PyObject *)self;
}

static PyMemberDef sixpoint_members[] = {
    {"engine", T_OBJECT, offsetof(SixPointReadObject, engine), READONLY, "the engine read"},
    {"fallback", T_OBJECT, offsetof(SixPointReadObject, fallback), READONLY,
     "the Python property's read, for the states the C code does not handle"},
    {"which", T_INT, offsetof(SixPointReadObject, which), READONLY,
     "0: position (AP1), 1: position_reached (AP8)"},
    {NULL}
};

static PyTypeObject SixPointReadType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "opentmcl._accel.SixPointRead",
    .tp_basicsize = sizeof(SixPointReadObject),
    .tp_dealloc = (destructor)sixpoint_dealloc,
    .tp_vectorcall_offset = offsetof(SixPointReadObject, vectorcall),
    .tp_call = PyVectorcall_Call,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_doc = "A six-point engine's position or position_reached, evaluated in C.",
    .tp_traverse = (traverseproc)sixpoint_traverse,
    .tp_clear = (inquiry)sixpoint_clear,
    .tp_members = sixpoint_members,
};

/* ---------------------------------------------------------------------------------------- */
/* Packed                                                                                   */

typedef struct {
    PyObject_HEAD
    PyObject *head;   /* the four bytes */
    PyObject *read;
    PyObject *slow;
    unsigned int head_sum;
    vectorcallfunc vectorcall;
} PackedObject;

static PyTypeObject PackedType;

static PyObject *
packed_reply_of(PackedObject *self, PyObject *value)
{
    const unsigned char *head = (const unsigned char *)PyBytes_AS_STRING(self->head);
    long long v;
    int overflow;
    uint32_t u;
    if (!PyLong_Check(value))
        return PyObject_CallOneArg(self->slow, value);
    v = PyLong_AsLongLongAndOverflow(value, &overflow);
    if (overflow) {
        u = (uint32_t)PyLong_AsUnsignedLongLongMask(value);  /* to_int32: the low 32 bits */
        if (PyErr_Occurred())
            return NULL;
    }
    else {
        if (v == -1 && PyErr_Occurred())
            return NULL;
        u = (uint32_t)(unsigned long long)v;
    }
    return reply9(head, self->head_sum, u);
}

static PyObject *
packed_vectorcall(PyObject *callable, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    PackedObject *self = (PackedObject *)callable;
    PyObject *value, *out;
    (void)args;
    if (PyVectorcall_NARGS(nargsf) != 0 || (kwnames && PyTuple_GET_SIZE(kwnames))) {
        PyErr_SetString(PyExc_TypeError, "a pre-bound handler takes no arguments");
        return NULL;
    }
    if (!self->read || !self->slow) {
        PyErr_SetString(PyExc_ReferenceError, "the pre-bound handler was cleared");  /* by the GC */
        return NULL;
    }
#if HAVE_INT128
    if (Py_TYPE(self->read) == &SixPointReadType && ((SixPointReadObject *)self->read)->engine
        && ((SixPointReadObject *)self->read)->fallback) {
        SixPointReadObject *r = (SixPointReadObject *)self->read;
        long long v;
        if (sixpoint_value(r->engine, r->which, &v, &r->cache) == R_VALUE)
            return reply9((const unsigned char *)PyBytes_AS_STRING(self->head), self->head_sum,
                          (uint32_t)(unsigned long long)v);
        value = PyObject_CallNoArgs(r->fallback);
    }
    else
#endif
    {
        value = PyObject_CallNoArgs(self->read);
    }
    if (!value)
        return NULL;
    out = packed_reply_of(self, value);
    Py_DECREF(value);
    return out;
}

static int
packed_traverse(PackedObject *self, visitproc visit, void *arg)
{
    Py_VISIT(self->read);
    Py_VISIT(self->slow);
    return 0;
}

static int
packed_clear(PackedObject *self)
{
    Py_CLEAR(self->read);
    Py_CLEAR(self->slow);
    return 0;
}

static void
packed_dealloc(PackedObject *self)
{
    PyObject_GC_UnTrack(self);
    packed_clear(self);
    Py_CLEAR(self->head);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *
packed(PyObject *module, PyObject *args)
{
    PyObject *head, *read, *slow;
    PackedObject *self;
    const unsigned char *h;
    (void)module;
    if (!PyArg_ParseTuple(args, "SOO:packed", &head, &read, &slow))
        return NULL;
    if (!PyBytes_CheckExact(head) || PyBytes_GET_SIZE(head) != 4) {
        PyErr_SetString(PyExc_ValueError, "head must be 4 bytes");
        return NULL;
    }
    if (!PyCallable_Check(read) || !PyCallable_Check(slow)) {
        PyErr_SetString(PyExc_TypeError, "read and slow must be callable");
        return NULL;
    }
    self = PyObject_GC_New(PackedObject, &PackedType);
    if (!self)
        return NULL;
    h = (const unsigned char *)PyBytes_AS_STRING(head);
    Py_INCREF(head);
    Py_INCREF(read);
    Py_INCREF(slow);
    self->head = head;
    self->read = read;
    self->slow = slow;
    self->head_sum = (unsigned int)h[0] + h[1] + h[2] + h[3];
    self->vectorcall = packed_vectorcall;
    PyObject_GC_Track(self);
    return (PyObject *)self;
}

static PyMemberDef packed_members[] = {
    {"head", T_OBJECT, offsetof(PackedObject, head), READONLY, "the reply's first four bytes"},
    {"read", T_OBJECT, offsetof(PackedObject, read), READONLY, "the value's read"},
    {NULL}
};

static PyTypeObject PackedType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "opentmcl._accel.Packed",
    .tp_basicsize = sizeof(PackedObject),
    .tp_dealloc = (destructor)packed_dealloc,
    .tp_vectorcall_offset = offsetof(PackedObject, vectorcall),
    .tp_call = PyVectorcall_Call,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_doc = "A pre-bound read's reply (dispatch._packed), packed in C.",
    .tp_traverse = (traverseproc)packed_traverse,
    .tp_clear = (inquiry)packed_clear,
    .tp_members = packed_members,
};

/* ---------------------------------------------------------------------------------------- */
/* Handle                                                                                   */

typedef struct {
    PyObject_HEAD
    PyObject *vm;
    PyObject *method;  /* type(vm)'s `handle` when this object was made (NULL: none) */
    vectorcallfunc vectorcall;
} HandleObject;

static PyTypeObject HandleType;

/* the pre-bound entry of `frame`: a new reference, Py_None when there is none, NULL on error */
static PyObject *
lookup_request(PyObject *vm, PyObject *frame)
{
    PyObject *requests = PyObject_GetAttr(vm, s_requests);
    PyObject *fast;
    if (!requests)
        return NULL;
    if (PyDict_CheckExact(requests)) {
        fast = PyDict_GetItemWithError(requests, frame);
        Py_XINCREF(fast);
        if (!fast && !PyErr_Occurred()) {
            fast = Py_None;
            Py_INCREF(fast);
        }
    }
    else {
        fast = PyObject_CallMethod(requests, "get", "O", frame);
    }
    Py_DECREF(requests);
    if (!fast && PyErr_ExceptionMatches(PyExc_TypeError)) {  /* a mutable buffer */
        PyErr_Clear();
        fast = Py_None;
        Py_INCREF(fast);
    }
    return fast;
}

/* the fast path once the entry is known: heartbeat, sync, entry() */
static PyObject *
handle_fast(PyObject *vm, PyObject *fast, PyObject *heartbeat)
{
    PyObject *now, *last, *synced, *r;
    int same;
    now = PyObject_GetAttr(vm, s_now);
    if (!now)
        return NULL;
    last = PyObject_GetAttr(vm, s_last_command);
    if (!last || PyObject_SetItem(last, heartbeat, now) < 0
        || PyObject_SetAttr(vm, s_heartbeat_fired, Py_False) < 0) {
        Py_XDECREF(last);
        Py_DECREF(now);
        return NULL;
    }
    Py_DECREF(last);
    synced = PyObject_GetAttr(vm, s_synced_at);
    if (!synced) {
        Py_DECREF(now);
        return NULL;
    }
    same = synced == now ? 1 : PyObject_RichCompareBool(synced, now, Py_EQ);
    Py_DECREF(synced);
    Py_DECREF(now);
    if (same < 0)
        return NULL;
    if (!same) {
        r = PyObject_CallMethodNoArgs(vm, s_sync_engines);
        if (!r)
            return NULL;
        Py_DECREF(r);
    }
    return PyObject_CallNoArgs(fast);
}

/* the arguments of handle(frame, *, interface="serial"): 0, or -1 with a TypeError set */
static int
handle_args(PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames, PyObject **frame,
            PyObject **interface)
{
    Py_ssize_t i, nkw = kwnames ? PyTuple_GET_SIZE(kwnames) : 0;
    if (nargs > 1) {
        PyErr_Format(PyExc_TypeError, "handle() takes 1 positional argument but %zd were given", nargs);
        return -1;
    }
    *frame = nargs ? args[0] : NULL;
    *interface = s_serial;
    for (i = 0; i < nkw; i++) {
        PyObject *name = PyTuple_GET_ITEM(kwnames, i);
        if (PyUnicode_Check(name) && PyUnicode_Compare(name, s_interface) == 0) {
            *interface = args[nargs + i];
        }
        else if (PyUnicode_Check(name) && PyUnicode_CompareWithASCIIString(name, "frame") == 0
                 && !*frame) {
            *frame = args[nargs + i];
        }
        else {
            PyErr_Format(PyExc_TypeError, "handle() got an unexpected or repeated keyword argument %R",
                         name);
            return -1;
        }
    }
    if (!*frame) {
        PyErr_SetString(PyExc_TypeError, "handle() missing 1 required positional argument: 'frame'");
        return -1;
    }
    return 0;
}

/* type(vm).handle is no longer the method this object stands for (patched onto the class, or
   vm.__class__ reassigned after the module was built): call that one, as the pure path does */
static PyObject *
handle_rebound(PyObject *vm, PyObject *method, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    PyObject *bound, *out;
    descrgetfunc get;
    if (!method) {
        PyErr_Format(PyExc_AttributeError, "'%.100s' object has no attribute 'handle'", Py_TYPE(vm)->tp_name);
        return NULL;
    }
    get = Py_TYPE(method)->tp_descr_get;
    if (!get)
        return PyObject_Vectorcall(method, args, nargsf, kwnames);
    Py_INCREF(method);  /* the descriptor's __get__ may run code that drops it from the class */
    bound = get(method, vm, (PyObject *)Py_TYPE(vm));
    Py_DECREF(method);
    if (!bound)
        return NULL;
    out = PyObject_Vectorcall(bound, args, nargsf, kwnames);
    Py_DECREF(bound);
    return out;
}

static PyObject *
handle_vectorcall(PyObject *callable, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    HandleObject *self = (HandleObject *)callable;
    PyObject *vm = self->vm;
    PyObject *frame, *interface, *fast, *heartbeat, *out, *method;

    if (!vm) {
        PyErr_SetString(PyExc_ReferenceError, "the compiled handle was cleared (its module is gone)");
        return NULL;
    }
    method = _PyType_Lookup(Py_TYPE(vm), s_handle);  /* borrowed; the type's method cache */
    if (method != self->method)
        return handle_rebound(vm, method, args, nargsf, kwnames);
    if (handle_args(args, PyVectorcall_NARGS(nargsf), kwnames, &frame, &interface) < 0)
        return NULL;
    fast = lookup_request(vm, frame);
    if (!fast)
        return NULL;
    heartbeat = PyDict_GetItemWithError(heartbeat_of, interface);  /* _HEARTBEAT_OF.get(interface) */
    if (!heartbeat && PyErr_Occurred()) {
        Py_DECREF(fast);
        return NULL;
    }
    if (fast != Py_None && heartbeat) {
        Py_INCREF(heartbeat);
        out = handle_fast(vm, fast, heartbeat);
        Py_DECREF(heartbeat);
        Py_DECREF(fast);
        return out;
    }
    Py_DECREF(fast);
    return PyObject_CallMethodObjArgs(vm, s_handle_general, frame, interface, NULL);
}

static PyObject *
handle_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    PyObject *vm;
    HandleObject *self;
    static char *kwlist[] = {"vm", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O:Handle", kwlist, &vm))
        return NULL;
    self = (HandleObject *)type->tp_alloc(type, 0);
    if (!self)
        return NULL;
    Py_INCREF(vm);
    self->vm = vm;
    self->method = _PyType_Lookup(Py_TYPE(vm), s_handle);
    Py_XINCREF(self->method);
    self->vectorcall = handle_vectorcall;
    return (PyObject *)self;
}

static int
handle_traverse(HandleObject *self, visitproc visit, void *arg)
{
    Py_VISIT(self->vm);
    Py_VISIT(self->method);
    return 0;
}

static int
handle_clear(HandleObject *self)
{
    Py_CLEAR(self->vm);
    Py_CLEAR(self->method);
    return 0;
}

static void
handle_dealloc(HandleObject *self)
{
    PyObject_GC_UnTrack(self);
    handle_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

/* __wrapped__: the Python method this object stands for, bound to the vm (inspect.signature
   follows it: server/bus.py asks whether `handle` takes `interface`) */
static PyObject *
handle_wrapped(HandleObject *self, void *closure)
{
    PyObject *func;
    PyObject *out;
    (void)closure;
    if (!self->vm) {
        PyErr_SetString(PyExc_AttributeError, "__wrapped__");
        return NULL;
    }
    func = PyObject_GetAttr((PyObject *)Py_TYPE(self->vm), s_handle);
    if (!func)
        return NULL;
    out = PyMethod_New(func, self->vm);
    Py_DECREF(func);
    return out;
}

/* copy.deepcopy and pickle: Handle(vm) again, on the copy of the module (the pure module has no
   instance attribute `handle`, its copies just work) */
static PyObject *
handle_reduce(HandleObject *self, PyObject *Py_UNUSED(ignored))
{
    if (!self->vm) {
        PyErr_SetString(PyExc_TypeError, "cannot pickle a cleared compiled handle");
        return NULL;
    }
    return Py_BuildValue("O(O)", (PyObject *)Py_TYPE(self), self->vm);
}

static PyMethodDef handle_methods[] = {
    {"__reduce__", (PyCFunction)handle_reduce, METH_NOARGS, "Handle(vm): pickle and copy.deepcopy"},
    {NULL, NULL, 0, NULL}
};

static PyObject *
handle_repr(HandleObject *self)
{
    return PyUnicode_FromFormat("<compiled handle of %R>", self->vm);
}

static PyGetSetDef handle_getset[] = {
    {"__wrapped__", (getter)handle_wrapped, NULL, "VirtualModule.handle bound to the module", NULL},
    {NULL}
};

static PyMemberDef handle_members[] = {
    {"__self__", T_OBJECT, offsetof(HandleObject, vm), READONLY, "the virtual module"},
    {NULL}
};

static PyTypeObject HandleType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "opentmcl._accel.Handle",
    .tp_basicsize = sizeof(HandleObject),
    .tp_dealloc = (destructor)handle_dealloc,
    .tp_vectorcall_offset = offsetof(HandleObject, vectorcall),
    .tp_repr = (reprfunc)handle_repr,
    .tp_call = PyVectorcall_Call,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_doc = "Handle(vm): vm.handle(frame, *, interface='serial') in C (VirtualModule.handle).",
    .tp_traverse = (traverseproc)handle_traverse,
    .tp_clear = (inquiry)handle_clear,
    .tp_members = handle_members,
    .tp_methods = handle_methods,
    .tp_getset = handle_getset,
    .tp_new = handle_new,
};

/* ---------------------------------------------------------------------------------------- */
/* EngineSync                                                                               */

/* EngineSync(cls)(engines, now): the loop of `VirtualModule._sync_engines` (firmware/vm.py),
   `for e in engines: if e.now < now: e.advance(now)`. For an engine of exactly `cls` (the
   six-point engine) whose class still has the `advance` this object was made with, and whose
   first queued piece holds at `now` (no end k1 <= now: SixPointRampEngine.advance would drop
   nothing), the call is its effect: `e.now = now`. Every other engine is called. */
typedef struct {
    PyObject_HEAD
    PyObject *cls;
    PyObject *advance;  /* cls's `advance` when this object was made */
    vectorcallfunc vectorcall;
} EngineSyncObject;

static PyTypeObject EngineSyncType;

/* does the first queued piece of `engine` hold at `now`? 1 yes, 0 no or unknown (call advance) */
static int
first_piece_holds(PyObject *engine, PyObject *now)
{
    PyObject *queue, *pieces, *seg, *k1;
    int rc = 0;
    queue = PyObject_GetAttr(engine, s_queue);
    if (!queue) {
        PyErr_Clear();  /* advance() raises it again, or knows better */
        return 0;
    }
    pieces = PyObject_GetAttr(queue, s_pieces);
    Py_DECREF(queue);
    if (!pieces) {
        PyErr_Clear();
        return 0;
    }
    if (PyList_CheckExact(pieces) && PyList_GET_SIZE(pieces) >= 1) {
        seg = PyList_GET_ITEM(pieces, 0);
        if (PyTuple_Check(seg) && PyTuple_GET_SIZE(seg) == 6) {
            k1 = PyTuple_GET_ITEM(seg, 1);
            if (k1 == Py_None)
                rc = 1;
            else if (PyLong_CheckExact(k1))
                rc = PyObject_RichCompareBool(k1, now, Py_GT);  /* two ints: no error */
        }
    }
    Py_DECREF(pieces);
    return rc < 0 ? 0 : rc;
}

static int
sync_one(EngineSyncObject *self, PyObject *engine, PyObject *now, int inline_ok)
{
    PyObject *at, *r;
    int behind;
    at = PyObject_GetAttr(engine, s_now);
    if (!at)
        return -1;
    behind = PyObject_RichCompareBool(at, now, Py_LT);
    Py_DECREF(at);
    if (behind <= 0)
        return behind;
    if (inline_ok && Py_TYPE(engine) == (PyTypeObject *)self->cls && first_piece_holds(engine, now))
        return PyObject_SetAttr(engine, s_now, now);
    r = PyObject_CallMethodOneArg(engine, s_advance, now);
    if (!r)
        return -1;
    Py_DECREF(r);
    return 0;
}

static PyObject *
engine_sync_vectorcall(PyObject *callable, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    EngineSyncObject *self = (EngineSyncObject *)callable;
    PyObject *engines, *now;
    Py_ssize_t i;
    int inline_ok;
    if (PyVectorcall_NARGS(nargsf) != 2 || (kwnames && PyTuple_GET_SIZE(kwnames))) {
        PyErr_SetString(PyExc_TypeError, "EngineSync takes two positional arguments: engines, now");
        return NULL;
    }
    if (!self->cls) {
        PyErr_SetString(PyExc_ReferenceError, "the engine sync was cleared");  /* by the GC */
        return NULL;
    }
    engines = args[0];
    now = args[1];
    if (!PyList_CheckExact(engines)) {
        PyErr_SetString(PyExc_TypeError, "engines must be a list");
        return NULL;
    }
    /* SixPointRampEngine.advance takes an int as it is; a class patched since goes through the call */
    inline_ok = PyLong_CheckExact(now) && _PyType_Lookup((PyTypeObject *)self->cls, s_advance) == self->advance;
    Py_INCREF(engines);
    for (i = 0; i < PyList_GET_SIZE(engines); i++) {  /* the size again: a call may change the list */
        PyObject *engine = PyList_GET_ITEM(engines, i);
        int rc;
        Py_INCREF(engine);
        rc = sync_one(self, engine, now, inline_ok);
        Py_DECREF(engine);
        if (rc < 0) {
            Py_DECREF(engines);
            return NULL;
        }
    }
    Py_DECREF(engines);
    Py_RETURN_NONE;
}

static PyObject *
engine_sync_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    PyObject *cls, *advance;
    EngineSyncObject *self;
    static char *kwlist[] = {"cls", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O!:EngineSync", kwlist, &PyType_Type, &cls))
        return NULL;
    advance = _PyType_Lookup((PyTypeObject *)cls, s_advance);
    if (!advance || !PyFunction_Check(advance)) {
        PyErr_SetString(PyExc_TypeError, "cls must have a Python method advance");
        return NULL;
    }
    self = (EngineSyncObject *)type->tp_alloc(type, 0);
    if (!self)
        return NULL;
    Py_INCREF(cls);
    Py_INCREF(advance);
    self->cls = cls;
    self->advance = advance;
    self->vectorcall = engine_sync_vectorcall;
    return (PyObject *)self;
}

static int
engine_sync_traverse(EngineSyncObject *self, visitproc visit, void *arg)
{
    Py_VISIT(self->cls);
    Py_VISIT(self->advance);
    return 0;
}

static int
engine_sync_clear(EngineSyncObject *self)
{
    Py_CLEAR(self->cls);
    Py_CLEAR(self->advance);
    return 0;
}

static void
engine_sync_dealloc(EngineSyncObject *self)
{
    PyObject_GC_UnTrack(self);
    engine_sync_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyMemberDef engine_sync_members[] = {
    {"cls", T_OBJECT, offsetof(EngineSyncObject, cls), READONLY, "the engine class synced in C"},
    {NULL}
};

static PyTypeObject EngineSyncType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "opentmcl._accel.EngineSync",
    .tp_basicsize = sizeof(EngineSyncObject),
    .tp_dealloc = (destructor)engine_sync_dealloc,
    .tp_vectorcall_offset = offsetof(EngineSyncObject, vectorcall),
    .tp_call = PyVectorcall_Call,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_doc = "EngineSync(cls)(engines, now): VirtualModule._sync_engines' loop in C.",
    .tp_traverse = (traverseproc)engine_sync_traverse,
    .tp_clear = (inquiry)engine_sync_clear,
    .tp_members = engine_sync_members,
    .tp_new = engine_sync_new,
};

/* ---------------------------------------------------------------------------------------- */
/* module                                                                                   */

static PyMethodDef accel_methods[] = {
    {"packed", packed, METH_VARARGS,
     "packed(head, read, slow): the reply of read() behind the 4-byte head (dispatch._packed); "
     "slow(value) answers a value that is not an int."},
    {"sixpoint_read", sixpoint_read, METH_VARARGS,
     "sixpoint_read(engine, which, fallback): a SixPointRampEngine's position (which 0) or "
     "position_reached (which 1) in C; fallback() answers the states the C code leaves alone."},
    {NULL, NULL, 0, NULL}
};

static struct PyModuleDef accel_module = {
    .m_base = PyModuleDef_HEAD_INIT,
    .m_name = "opentmcl._accel",
    .m_doc = "Compiled twin of the virtual module's request path (opentmcl.accel).",
    .m_size = -1,
    .m_methods = accel_methods,
};

static int
build_heartbeat_table(void)
{
    /* the same table as firmware/vm.py _HEARTBEAT_OF (tests/accel compare them) */
    static const char *links[][2] = {
        {"serial", "serial"}, {"rs485", "serial"}, {"rs232", "serial"}, {"usb", "serial"},
        {"can", "can"},
    };
    size_t i;
    heartbeat_of = PyDict_New();
    if (!heartbeat_of)
        return -1;
    for (i = 0; i < sizeof links / sizeof links[0]; i++) {
        PyObject *k = PyUnicode_InternFromString(links[i][0]);
        PyObject *v = PyUnicode_InternFromString(links[i][1]);
        int rc = (k && v) ? PyDict_SetItem(heartbeat_of, k, v) : -1;
        Py_XDECREF(k);
        Py_XDECREF(v);
        if (rc < 0)
            return -1;
    }
    return 0;
}

PyMODINIT_FUNC
PyInit__accel(void)
{
    PyObject *m;
    if (intern_names() < 0 || build_heartbeat_table() < 0)
        return NULL;
#if HAVE_INT128
    if (!(sixty_four = PyLong_FromLong(64)))
        return NULL;
#endif
    if (PyType_Ready(&HandleType) < 0 || PyType_Ready(&PackedType) < 0
        || PyType_Ready(&SixPointReadType) < 0 || PyType_Ready(&EngineSyncType) < 0)
        return NULL;
    m = PyModule_Create(&accel_module);
    if (!m)
        return NULL;
    Py_INCREF(&HandleType);
    Py_INCREF(&PackedType);
    Py_INCREF(&SixPointReadType);
    Py_INCREF(&EngineSyncType);
    Py_INCREF(heartbeat_of);
    if (PyModule_AddObject(m, "Handle", (PyObject *)&HandleType) < 0
        || PyModule_AddObject(m, "Packed", (PyObject *)&PackedType) < 0
        || PyModule_AddObject(m, "SixPointRead", (PyObject *)&SixPointReadType) < 0
        || PyModule_AddObject(m, "EngineSync", (PyObject *)&EngineSyncType) < 0
        || PyModule_AddObject(m, "HEARTBEAT_OF", heartbeat_of) < 0
        || PyModule_AddIntConstant(m, "HAVE_INT128", HAVE_INT128) < 0) {
        Py_DECREF(m);
        return NULL;
    }
#if HAVE_INT128
    {
        /* PSCALE for the tests to compare with motion/segments.py */
        i128 ps = PSCALE;
        PyObject *hi = PyLong_FromUnsignedLongLong((unsigned long long)((u128)ps >> 64));
        PyObject *lo = PyLong_FromUnsignedLongLong((unsigned long long)ps);
        PyObject *shifted = hi ? PyNumber_Lshift(hi, sixty_four) : NULL;
        PyObject *value = (shifted && lo) ? PyNumber_Or(shifted, lo) : NULL;
        Py_XDECREF(hi);
        Py_XDECREF(lo);
        Py_XDECREF(shifted);
        if (!value || PyModule_AddObject(m, "PSCALE", value) < 0) {
            Py_XDECREF(value);
            Py_DECREF(m);
            return NULL;
        }
    }
#endif
    return m;
}
