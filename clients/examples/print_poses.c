/* print_poses: the smallest C client. Prints the frame and index fingertip of each new pose.
 * Build against the installed library:  cc print_poses.c $(pkg-config --cflags --libs handtrack)
 * Usage: print_poses [SHM_NAME [COUNT]] */
#include <handtrack/client.h>

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char** argv) {
  const char* name = argc > 1 ? argv[1] : HANDTRACK_DEFAULT_SHM_NAME;
  long count = argc > 2 ? strtol(argv[2], NULL, 10) : 10;
  handtrack_client* client = NULL;
  int status = handtrack_open(name, &client);
  if (status != HANDTRACK_OK) {
    fprintf(stderr, "print_poses: %s (%s)\n", handtrack_strerror(status), handtrack_error_detail());
    return 1;
  }
  handtrack_pose pose;
  long printed = 0;
  while (printed < count) {
    status = handtrack_wait_next(client, &pose, 2000000000LL); /* 2 s */
    if (status == HANDTRACK_OK) {
      printf("frame %llu %s index tip %.1f %.1f %.1f mm (missed %llu)\n",
             (unsigned long long)pose.frame, handtrack_state_name(pose.state),
             pose.fingertips_mm[1][0], pose.fingertips_mm[1][1], pose.fingertips_mm[1][2],
             (unsigned long long)handtrack_missed(client));
      ++printed;
    } else if (status < 0 && status != HANDTRACK_ERR_WRITER_DEAD && status != HANDTRACK_ERR_WRITER_STOPPED) {
      fprintf(stderr, "print_poses: %s\n", handtrack_strerror(status));
      break;
    } else if (status == HANDTRACK_TIMEOUT) {
      fprintf(stderr, "print_poses: no pose for 2 s\n");
      break;
    }
  }
  handtrack_close(client);
  return printed == count ? 0 : 1;
}
