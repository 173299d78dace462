/* print_poses: the smallest C client. Prints each new frame with every hand in it: its id,
 * handedness, state and index fingertip.
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
  handtrack_frame frame;
  long printed = 0;
  while (printed < count) {
    status = handtrack_wait_next(client, &frame, 2000000000LL); /* 2 s */
    if (status == HANDTRACK_OK) {
      printf("frame %llu (missed %llu):", (unsigned long long)frame.frame,
             (unsigned long long)handtrack_missed(client));
      if (frame.hand_count == 0) printf(" no hand");
      for (uint32_t i = 0; i < frame.hand_count; ++i) {
        const handtrack_hand* hand = &frame.hands[i];
        printf("%s hand %u %s %s index tip %.1f %.1f %.1f mm", i > 0 ? ";" : "", (unsigned)hand->hand_id,
               handtrack_handedness_name(hand->handedness), handtrack_state_name(hand->state),
               hand->fingertips_mm[1][0], hand->fingertips_mm[1][1], hand->fingertips_mm[1][2]);
      }
      printf("\n");
      ++printed;
    } else if (status < 0 && status != HANDTRACK_ERR_WRITER_DEAD && status != HANDTRACK_ERR_WRITER_STOPPED) {
      fprintf(stderr, "print_poses: %s (%s)\n", handtrack_strerror(status), handtrack_error_detail());
      break;
    } else if (status == HANDTRACK_TIMEOUT) {
      fprintf(stderr, "print_poses: no frame for 2 s\n");
      break;
    }
  }
  handtrack_close(client);
  return printed == count ? 0 : 1;
}
