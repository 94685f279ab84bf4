/*
 * The C side of internodes' PETSc body solver: conjugate gradients preconditioned by
 * smoothed-aggregation algebraic multigrid (KSPCG + PCGAMG) on one body's stiffness matrix.
 * Compiled by build.rs only with the cargo feature `petsc`; src/linalg/petsc/mod.rs is its only
 * caller and serializes every call (PETSc is not thread-safe), except that
 * internodes_cgamg_precondition may run on distinct objects at once (the audit is in mod.rs).
 *
 * Every function returns 0 or a PETSc error code; on error `*step` names the call that failed
 * (a static string). PETSc's own error printing is replaced by PetscReturnErrorHandler at
 * initialization, so an error is only a return code.
 *
 * Communicators cross the Rust boundary as MPI Fortran handles (MPI_Fint, an int): their
 * C type MPI_Comm differs between MPI implementations (a pointer in Open MPI, an int in
 * MPICH), the Fortran handle does not.
 */
#include <stdint.h>
#include <string.h>
#include <petscksp.h>

#define TRY(call)                   \
    do {                            \
        PetscErrorCode ierr_ = (call); \
        if (ierr_) {                \
            *step = #call;          \
            return (int)ierr_;      \
        }                           \
    } while (0)

/* A body's operator and its preconditioner, built once, and the vectors of one solve. */
typedef struct {
    Mat a;
    KSP ksp;
    Vec b, x;
    PetscInt n;
} InternodesCgAmg;

/* PetscInitializeNoArguments, once per process (the caller guarantees it), without PETSc's
 * signal handlers (a crash stays a crash of this process, reported by Rust, not a PETSc
 * message), with errors returned rather than printed. The options database also reads the
 * PETSC_OPTIONS environment variable (e.g. -ksp_view, -log_view to inspect a solve). */
int internodes_petsc_initialize(const char **step)
{
    TRY(PetscOptionsSetValue(NULL, "-no_signal_handler", NULL));
    TRY(PetscInitializeNoArguments());
    TRY(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    return 0;
}

/* Whether the options database holds exactly what internodes_petsc_initialize put there
 * (-no_signal_handler): 1 if so, 0 if anything else came in (the PETSC_OPTIONS or
 * PETSC_OPTIONS_YAML environment variables, a .petscrc file). Options such as
 * -ksp_converged_reason or -info make a V-cycle print through viewers shared by all objects;
 * the caller then keeps every application exclusive. */
int internodes_petsc_options_are_ours(int *ours, const char **step)
{
    char *all = NULL;
    TRY(PetscOptionsGetAll(NULL, &all));
    size_t start = 0, end = strlen(all);
    while (start < end && all[start] == ' ') start++;
    while (end > start && all[end - 1] == ' ') end--;
    *ours = (end - start == strlen("-no_signal_handler") &&
             !strncmp(all + start, "-no_signal_handler", end - start));
    PetscFree(all);
    return 0;
}

/* PETSC_COMM_SELF as a Fortran handle. */
MPI_Fint internodes_petsc_comm_self(void)
{
    return MPI_Comm_c2f(PETSC_COMM_SELF);
}

/* PETSC_COMM_WORLD (MPI_COMM_WORLD: every rank of the run) as a Fortran handle. */
MPI_Fint internodes_petsc_comm_world(void)
{
    return MPI_Comm_c2f(PETSC_COMM_WORLD);
}

/* This process's rank and the number of ranks in PETSC_COMM_WORLD. */
int internodes_mpi_rank_size(int *rank, int *size, const char **step)
{
    TRY(MPI_Comm_rank(PETSC_COMM_WORLD, rank));
    TRY(MPI_Comm_size(PETSC_COMM_WORLD, size));
    return 0;
}

/* Every rank's `local` (counts[r] values from rank r) into `global`, in rank order, on every
 * rank (MPI_Allgatherv over PETSC_COMM_WORLD; displs[r] is where rank r's values start), or
 * with `root_only` on rank 0 alone (MPI_Gatherv: `global`, `counts` and `displs` are read on
 * rank 0 only). */
int internodes_mpi_gather(const double *local, int count, double *global, const int *counts,
                          const int *displs, int root_only, const char **step)
{
    if (root_only)
        TRY(MPI_Gatherv(local, count, MPI_DOUBLE, global, counts, displs, MPI_DOUBLE, 0,
                        PETSC_COMM_WORLD));
    else
        TRY(MPI_Allgatherv(local, count, MPI_DOUBLE, global, counts, displs, MPI_DOUBLE,
                           PETSC_COMM_WORLD));
    return 0;
}

/* Each rank's values for every rank: send_counts[r] values of `sent` (from send_displs[r]) to
 * rank r, and recv_counts[r] values from rank r into `received` (from recv_displs[r])
 * (MPI_Alltoallv over PETSC_COMM_WORLD). The counts each rank receives are exchanged first
 * (internodes_mpi_exchange_counts). */
int internodes_mpi_exchange(const double *sent, const int *send_counts, const int *send_displs,
                            double *received, const int *recv_counts, const int *recv_displs,
                            const char **step)
{
    TRY(MPI_Alltoallv(sent, send_counts, send_displs, MPI_DOUBLE, received, recv_counts,
                      recv_displs, MPI_DOUBLE, PETSC_COMM_WORLD));
    return 0;
}

/* How many values each rank sends this one: send_counts[r] (one value a rank) is what this
 * rank sends rank r, recv_counts[r] what rank r sends it (MPI_Alltoall). */
int internodes_mpi_exchange_counts(const int *send_counts, int *recv_counts, const char **step)
{
    TRY(MPI_Alltoall(send_counts, 1, MPI_INT, recv_counts, 1, MPI_INT, PETSC_COMM_WORLD));
    return 0;
}

/* Rank 0's `len` bytes at `data` into `data` on every rank (every rank knows `len`: see
 * internodes_mpi_broadcast_length). In chunks, since MPI counts are ints. */
int internodes_mpi_broadcast(void *data, int64_t len, const char **step)
{
    const int64_t chunk = 1 << 30;
    for (int64_t at = 0; at < len; at += chunk) {
        int n = (int)(len - at < chunk ? len - at : chunk);
        TRY(MPI_Bcast((char *)data + at, n, MPI_BYTE, 0, PETSC_COMM_WORLD));
    }
    return 0;
}

/* The length rank 0 broadcasts next, on every rank (the first half of a broadcast). */
int internodes_mpi_broadcast_length(int64_t *len, const char **step)
{
    TRY(MPI_Bcast(len, 1, MPI_INT64_T, 0, PETSC_COMM_WORLD));
    return 0;
}

/* Rank r's count of what rank 0 scatters next: counts[r] of rank 0's `counts` (one value a
 * rank, read on rank 0 only) into `mine` on every rank (MPI_Scatter over PETSC_COMM_WORLD). */
int internodes_mpi_scatter_count(const int64_t *counts, int64_t *mine, const char **step)
{
    TRY(MPI_Scatter(counts, 1, MPI_INT64_T, mine, 1, MPI_INT64_T, 0, PETSC_COMM_WORLD));
    return 0;
}

/* Each rank's cells from rank 0: counts[r] cells of `width` values starting at cell displs[r]
 * of rank 0's `all` into `mine` (`count` cells) on rank r (MPI_Scatterv over PETSC_COMM_WORLD;
 * `all`, `counts` and `displs` are read on rank 0 only). Counted in cells, each an MPI type of
 * `width` uint32 values, so that the ints of MPI count up to 2^31 cells rather than values. */
int internodes_mpi_scatter_cells(const uint32_t *all, const int *counts, const int *displs,
                                 uint32_t *mine, int count, int width, const char **step)
{
    MPI_Datatype cell;
    TRY(MPI_Type_contiguous(width, MPI_UINT32_T, &cell));
    TRY(MPI_Type_commit(&cell));
    TRY(MPI_Scatterv(all, counts, displs, cell, mine, count, cell, 0, PETSC_COMM_WORLD));
    TRY(MPI_Type_free(&cell));
    return 0;
}

/* Ends every rank of the run with `code` (a rank that failed alone: the others may be waiting
 * for it in a collective call, and would wait for ever). */
void internodes_mpi_abort(int code)
{
    MPI_Abort(PETSC_COMM_WORLD, code);
}

/* PetscFinalize, which finalizes MPI (a rank that exits without it is reported by mpirun as
 * ended improperly). Every PETSc object must have been destroyed. */
int internodes_petsc_finalize(const char **step)
{
    TRY(PetscFinalize());
    return 0;
}

/* The generic text of a PETSc error code. */
const char *internodes_petsc_error_text(int code)
{
    const char *text = NULL;
    if (PetscErrorMessage((PetscErrorCode)code, &text, NULL) || !text) return "unknown PETSc error";
    return text;
}

/* The name of a KSPConvergedReason (e.g. "DIVERGED_ITS"). */
const char *internodes_ksp_reason_name(int reason)
{
    if (reason < -11 || reason > 9) return "UNKNOWN";
    const char *name = KSPConvergedReasons[reason];
    return name ? name : "UNKNOWN";
}

static int to_petsc_ints(const int64_t *from, size_t len, PetscInt **to, const char **step)
{
    TRY(PetscMalloc1(len, to));
    for (size_t k = 0; k < len; k++) {
        if (from[k] < 0 || from[k] > PETSC_MAX_INT) {
            PetscFree(*to);
            *step = "index conversion (an index exceeds PetscInt; PETSc is built with 32-bit indices)";
            return PETSC_ERR_ARG_OUTOFRANGE;
        }
        (*to)[k] = (PetscInt)from[k];
    }
    return 0;
}

/* The rows of a matrix whole on this process (SEQAIJ, created and sized) at their places in
 * another order of the nodes: our node k is node petsc_node[k] of PETSc's, so our dof
 * k * block + c is PETSc's petsc_node[k] * block + c, for rows and columns alike. Each row is
 * inserted with its columns sorted, into exactly the room preallocated for it, so that no
 * copy of the whole matrix is made besides PETSc's own. */
static int insert_permuted(Mat a, int64_t n, int64_t block, const int64_t *row_ptr,
                           const int64_t *col_idx, const double *values, const int64_t *petsc_node,
                           const char **step)
{
    PetscInt *lengths = NULL, *columns = NULL;
    PetscScalar *entries = NULL;
    int64_t longest = 0;
    int code = 0;

#define PETSC_DOF(dof) ((PetscInt)(petsc_node[(dof) / block] * block + (dof) % block))
    for (int64_t k = 0; k < n / block; k++) {
        if (petsc_node[k] < 0 || petsc_node[k] >= n / block) {
            *step = "checking the node order (a node's place beyond the nodes)";
            return PETSC_ERR_ARG_OUTOFRANGE;
        }
    }
    TRY(PetscMalloc1(n, &lengths));
    for (int64_t r = 0; r < n; r++) {
        int64_t length = row_ptr[r + 1] - row_ptr[r];
        lengths[PETSC_DOF(r)] = (PetscInt)length;
        if (length > longest) longest = length;
    }
    code = MatSeqAIJSetPreallocation(a, 0, lengths);
    PetscFree(lengths);
    if (code) {
        *step = "MatSeqAIJSetPreallocation (the permuted rows' lengths)";
        return code;
    }
    TRY(PetscMalloc2(longest, &columns, longest, &entries));
    for (int64_t r = 0; r < n && !code; r++) {
        PetscInt row = PETSC_DOF(r), length = (PetscInt)(row_ptr[r + 1] - row_ptr[r]);
        for (PetscInt e = 0; e < length; e++) {
            int64_t column = col_idx[row_ptr[r] + e];
            if (column < 0 || column >= n) {
                code = PETSC_ERR_ARG_OUTOFRANGE;
                *step = "checking the column indices (one beyond the matrix)";
                break;
            }
            columns[e] = PETSC_DOF(column);
            entries[e] = values[row_ptr[r] + e];
        }
        if (!code) code = PetscSortIntWithScalarArray(length, columns, entries);
        if (!code) code = MatSetValues(a, 1, &row, length, columns, entries, INSERT_VALUES);
        if (code && !*step) *step = "inserting a permuted row";
    }
#undef PETSC_DOF
    PetscFree2(columns, entries);
    if (code) return code;
    TRY(MatAssemblyBegin(a, MAT_FINAL_ASSEMBLY));
    TRY(MatAssemblyEnd(a, MAT_FINAL_ASSEMBLY));
    return 0;
}

/* The rows as they are (AIJ: SEQAIJ on one process, MPIAIJ on several): both preallocation
 * calls are made, the one that does not match the type is a no-op. They copy i, j, values and
 * assemble. */
static int insert_as_they_are(Mat a, int64_t n, const int64_t *row_ptr, const int64_t *col_idx,
                              const double *values, const char **step)
{
    PetscInt *i = NULL, *j = NULL;
    int code;

    if ((code = to_petsc_ints(row_ptr, (size_t)n + 1, &i, step))) return code;
    if ((code = to_petsc_ints(col_idx, (size_t)row_ptr[n], &j, step))) {
        PetscFree(i);
        return code;
    }
    code = MatSeqAIJSetPreallocationCSR(a, i, j, values);
    if (!code) code = MatMPIAIJSetPreallocationCSR(a, i, j, values);
    PetscFree(i);
    PetscFree(j);
    if (code) *step = "creating the AIJ matrix from CSR arrays";
    return code;
}

static int build(InternodesCgAmg *s, MPI_Comm comm, int64_t n, int64_t block, const int64_t *row_ptr,
                 const int64_t *col_idx, const double *values, const int64_t *petsc_node,
                 const double *coords, double rtol, int64_t max_it, const char **step)
{
    Vec xyz = NULL;
    MatNullSpace near_null = NULL;
    PC pc;
    int code;

    s->n = (PetscInt)n;

    /* The matrix: AIJ with the node block size, so that GAMG aggregates nodes, not single
     * dofs; its rows as they are, or (on one process) at their places in PETSc's node order. */
    TRY(MatCreate(comm, &s->a));
    TRY(MatSetSizes(s->a, (PetscInt)n, (PetscInt)n, PETSC_DETERMINE, PETSC_DETERMINE));
    TRY(MatSetBlockSize(s->a, (PetscInt)block));
    TRY(MatSetType(s->a, MATAIJ));
    if (petsc_node) {
        PetscMPIInt size;
        TRY(MPI_Comm_size(comm, &size));
        if (size != 1) {
            *step = "a node order on several processes";
            return PETSC_ERR_SUP;
        }
        code = insert_permuted(s->a, n, block, row_ptr, col_idx, values, petsc_node, step);
    } else {
        code = insert_as_they_are(s->a, n, row_ptr, col_idx, values, step);
    }
    if (code) return code;
    TRY(MatSetOption(s->a, MAT_SPD, PETSC_TRUE));

    /* Near-null space: the rigid-body modes of the nodes (3 in 2D, 6 in 3D). */
    TRY(VecCreate(comm, &xyz));
    code = VecSetSizes(xyz, (PetscInt)n, PETSC_DETERMINE);
    if (!code) code = VecSetBlockSize(xyz, (PetscInt)block);
    if (!code) code = VecSetType(xyz, VECSTANDARD);
    if (!code) {
        PetscScalar *data;
        code = VecGetArray(xyz, &data);
        if (!code) {
            memcpy(data, coords, (size_t)n * sizeof(double));
            code = VecRestoreArray(xyz, &data);
        }
    }
    if (!code) code = MatNullSpaceCreateRigidBody(xyz, &near_null);
    if (!code) code = MatSetNearNullSpace(s->a, near_null);
    MatNullSpaceDestroy(&near_null);
    VecDestroy(&xyz);
    if (code) {
        *step = "setting the rigid-body near-null space";
        return code;
    }

    /* CG + GAMG. The convergence test reads the unpreconditioned residual, so that rtol bounds
     * ||b - A x|| / ||b|| (zero initial guess), the figure the caller checks. */
    TRY(KSPCreate(comm, &s->ksp));
    TRY(KSPSetOperators(s->ksp, s->a, s->a));
    TRY(KSPSetType(s->ksp, KSPCG));
    TRY(KSPGetPC(s->ksp, &pc));
    TRY(PCSetType(pc, PCGAMG));
    TRY(KSPSetNormType(s->ksp, KSP_NORM_UNPRECONDITIONED));
    TRY(KSPSetTolerances(s->ksp, (PetscReal)rtol, 0.0, PETSC_DEFAULT, (PetscInt)max_it));
    /* GAMG's defaults are only complete after SetFromOptions (without it its setup was 5x
     * slower in validation/benchmark.py); it also lets PETSC_OPTIONS add e.g. -ksp_view. */
    TRY(KSPSetFromOptions(s->ksp));
    TRY(MatCreateVecs(s->a, &s->x, &s->b));
    return 0;
}

/* The GAMG hierarchy of a built object (internodes_cgamg_create): a separate step, so that the
 * caller can free its own copy of the matrix first. */
int internodes_cgamg_set_up(InternodesCgAmg *s, const char **step)
{
    PC pc;
    PetscInt levels;
    PetscMPIInt size;
    PetscBool user_chose, user_chose_clear;
    /* On one process GAMG's Galerkin products P^T A P (SeqAIJ) take PETSc's "rap" algorithm
     * (P^T formed once, then R A P) instead of the default "scalable" one: the same products,
     * the set-up of the 1M hemisphere 32.2 s -> 21.0 s at the same peak (docs/decisions.md).
     * The option is set for this set-up alone, since on several processes (MPIAIJ) "rap" is no
     * algorithm and PETSc would refuse it; a -matptap_via the user gave is left to rule. */
    TRY(MPI_Comm_size(PetscObjectComm((PetscObject)s->a), &size));
    TRY(PetscOptionsHasName(NULL, NULL, "-matptap_via", &user_chose));
    const PetscBool choose_rap = size == 1 && !user_chose;
    if (choose_rap) TRY(PetscOptionsSetValue(NULL, "-matptap_via", "rap"));
    /* Each of GAMG's matrix products keeps the intermediate data of a reuse that never comes
     * (the hierarchy is built once). "-mat_product_clear" frees it as soon as each product is
     * computed, level by level, rather than all of it after the set-up (below): on several
     * ranks those data are as large as the products, and all levels' together made the set-up
     * the run's peak at 3M DOFs (docs/parallel.md). Set for this set-up alone, as above. */
    TRY(PetscOptionsHasName(NULL, NULL, "-mat_product_clear", &user_chose_clear));
    if (!user_chose_clear) TRY(PetscOptionsSetValue(NULL, "-mat_product_clear", NULL));
    PetscErrorCode set_up = KSPSetUp(s->ksp);
    if (choose_rap) TRY(PetscOptionsClearValue(NULL, "-matptap_via"));
    if (!user_chose_clear) TRY(PetscOptionsClearValue(NULL, "-mat_product_clear"));
    if (set_up) {
        *step = "KSPSetUp(s->ksp)";
        return (int)set_up;
    }
    TRY(KSPGetPC(s->ksp, &pc));
    /* GAMG makes its coarse operators P^T A P and its smoothed prolongators A P as PETSc
     * matrix products, each keeping the intermediate data of a reuse that never comes (the
     * hierarchy is built once): on several ranks it made a rank's hierarchy larger than the
     * whole serial one (docs/parallel.md). It is freed here; the matrices stay as they are. */
    TRY(PCMGGetLevels(pc, &levels));
    for (PetscInt level = 0; level < levels; level++) {
        KSP smoother;
        Mat operator, preconditioning, interpolation;
        TRY(PCMGGetSmoother(pc, level, &smoother));
        TRY(KSPGetOperators(smoother, &operator, &preconditioning));
        TRY(MatProductClear(operator));
        TRY(MatProductClear(preconditioning));
        if (level > 0) {
            TRY(PCMGGetInterpolation(pc, level, &interpolation));
            TRY(MatProductClear(interpolation));
        }
    }
    /* One V-cycle now, while the caller holds PETSc exclusively: PETSc finishes the set-up on
     * the first application (the coarse level's block Jacobi factors its LU in
     * PCSetUpOnBlocks, through PCSetUp, MatGetFactor and MatGetOrdering, which touch
     * process-wide registries and the event log). After it, an application writes only this
     * object's memory, which internodes_cgamg_precondition relies on (see mod.rs). */
    TRY(VecSet(s->b, 1.0));
    TRY(PCApply(pc, s->b, s->x));
    return 0;
}

/* y = A x, this rank's rows of x in and of y out. */
int internodes_cgamg_multiply(InternodesCgAmg *s, const double *x, double *y, const char **step)
{
    PetscScalar *data;

    TRY(VecGetArray(s->b, &data));
    memcpy(data, x, (size_t)s->n * sizeof(double));
    TRY(VecRestoreArray(s->b, &data));
    TRY(MatMult(s->a, s->b, s->x));
    TRY(VecGetArray(s->x, &data));
    memcpy(y, data, (size_t)s->n * sizeof(double));
    TRY(VecRestoreArray(s->x, &data));
    return 0;
}

/* The matrix's compressed rows as PETSc holds them on one process (SEQAIJ): PETSc's own arrays,
 * not copies: n + 1 row pointers and the column indices (PetscInt, *index_bytes each) and the
 * values. They stay where they are while the object lives: an assembled AIJ matrix moves them
 * only to insert a new nonzero, which nothing does here, and CG and GAMG only read them. The
 * pointers are taken before the Restore calls, which may clear them but free nothing here. */
int internodes_cgamg_rows(InternodesCgAmg *s, const void **row_ptr, const void **col_idx,
                          const double **values, int *index_bytes, const char **step)
{
    PetscInt n;
    const PetscInt *ia, *ja;
    const PetscScalar *a;
    PetscBool done;
    PetscMPIInt size;

    TRY(MPI_Comm_size(PetscObjectComm((PetscObject)s->a), &size));
    if (size != 1) {
        *step = "the rows of a matrix shared among ranks";
        return PETSC_ERR_SUP;
    }
    TRY(MatGetRowIJ(s->a, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
    if (!done || n != s->n) {
        *step = "MatGetRowIJ (no compressed rows)";
        return PETSC_ERR_SUP;
    }
    *row_ptr = ia;
    *col_idx = ja;
    TRY(MatRestoreRowIJ(s->a, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
    TRY(MatSeqAIJGetArrayRead(s->a, &a));
    *values = a;
    TRY(MatSeqAIJRestoreArrayRead(s->a, &a));
    *index_bytes = (int)sizeof(PetscInt);
    return 0;
}

void internodes_cgamg_destroy(InternodesCgAmg *s)
{
    if (!s) return;
    KSPDestroy(&s->ksp);
    MatDestroy(&s->a);
    VecDestroy(&s->b);
    VecDestroy(&s->x);
    PetscFree(s);
}

/* Builds the operator (n x n CSR, symmetric positive definite, `block` dofs per node,
 * interleaved: this rank's n rows) and its CG + GAMG solver on the communicator `fcomm`;
 * `petsc_node` (NULL, or on one process n / block values) puts our node k at place
 * petsc_node[k] of PETSc's order, in which every vector of a later call is then read and
 * written; `coords` holds the node coordinates in PETSc's order, `block` per node (n values).
 * The GAMG hierarchy is built by internodes_cgamg_set_up, which must follow before any solve
 * or application. */
int internodes_cgamg_create(MPI_Fint fcomm, int64_t n, int64_t block, const int64_t *row_ptr,
                            const int64_t *col_idx, const double *values, const int64_t *petsc_node,
                            const double *coords, double rtol, int64_t max_it,
                            InternodesCgAmg **out, const char **step)
{
    InternodesCgAmg *s = NULL;
    *out = NULL;
    if (n < 0 || n > PETSC_MAX_INT || block < 1 || n % block) {
        *step = "checking the sizes (n a multiple of the block size, within PetscInt)";
        return PETSC_ERR_ARG_OUTOFRANGE;
    }
    TRY(PetscCalloc1(1, &s));
    int code = build(s, MPI_Comm_f2c(fcomm), n, block, row_ptr, col_idx, values, petsc_node, coords,
                     rtol, max_it, step);
    if (code) {
        internodes_cgamg_destroy(s);
        return code;
    }
    *out = s;
    return 0;
}

/* Solves A x = rhs from x = 0 to the relative residual rtol: the iterations, the final residual
 * norm ||rhs - A x|| and the KSPConvergedReason (positive: converged). */
/* One application of the preconditioner alone, x = P^-1 rhs: one GAMG V-cycle. The caller may
 * run this on distinct objects from several threads at once (never on one object twice at
 * once, and never beside any other PETSc call): see "PETSc in a Rust process" in mod.rs. */
int internodes_cgamg_precondition(InternodesCgAmg *s, const double *rhs, double *x, const char **step)
{
    PetscScalar *data;
    PC pc;

    TRY(VecGetArray(s->b, &data));
    memcpy(data, rhs, (size_t)s->n * sizeof(double));
    TRY(VecRestoreArray(s->b, &data));
    TRY(KSPGetPC(s->ksp, &pc));
    TRY(PCApply(pc, s->b, s->x));
    TRY(VecGetArray(s->x, &data));
    memcpy(x, data, (size_t)s->n * sizeof(double));
    TRY(VecRestoreArray(s->x, &data));
    return 0;
}

int internodes_cgamg_solve(InternodesCgAmg *s, const double *rhs, double *x, double rtol,
                           int64_t *iterations, double *residual_norm, int *reason,
                           const char **step)
{
    PetscScalar *data;
    PetscInt its;
    PetscReal rnorm;
    KSPConvergedReason why;

    TRY(VecGetArray(s->b, &data));
    memcpy(data, rhs, (size_t)s->n * sizeof(double));
    TRY(VecRestoreArray(s->b, &data));
    TRY(VecSet(s->x, 0.0));
    TRY(KSPSetTolerances(s->ksp, (PetscReal)rtol, 0.0, PETSC_DEFAULT, PETSC_DEFAULT));
    TRY(KSPSolve(s->ksp, s->b, s->x));
    TRY(KSPGetIterationNumber(s->ksp, &its));
    TRY(KSPGetResidualNorm(s->ksp, &rnorm));
    TRY(KSPGetConvergedReason(s->ksp, &why));
    TRY(VecGetArray(s->x, &data));
    memcpy(x, data, (size_t)s->n * sizeof(double));
    TRY(VecRestoreArray(s->x, &data));
    *iterations = its;
    *residual_norm = rnorm;
    *reason = (int)why;
    return 0;
}
