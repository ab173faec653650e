#ifndef CSTREAMS_RUNTIME_COMMON_H
#define CSTREAMS_RUNTIME_COMMON_H

#ifndef CS_WG_SIZE
#error "CS_WG_SIZE comes from the program registry's device options"
#endif

/* A counter slot argument that means "write no counter". Matches kNoSlot on the host. */
#define CS_NO_SLOT 0xffffffffu

#define CS_GROUP_KERNEL __kernel __attribute__((reqd_work_group_size(CS_WG_SIZE, 1, 1)))

#endif
